# Install rules and the Debian package (CPack DEB) of the daemon.
#
# Every destination is relative to the root of the installed system, and the install prefix
# defaults to "/": `cmake --install build --prefix P` lays out under P exactly the tree the
# package unpacks at / (P/usr/bin/liod, P/etc/liod/liod.yaml, ...), and the unit's absolute
# paths (ExecStart=/usr/bin/liod) hold in both. scripts/check-package.sh builds and checks the
# package; README.md, "Running on the vehicle", installs it.
#
# Only the component `liod` is packaged (CPACK_INSTALL_CMAKE_PROJECTS): the developer tools keep
# install rules of their own outside the package.
if(CMAKE_INSTALL_PREFIX_INITIALIZED_TO_DEFAULT)
  set(CMAKE_INSTALL_PREFIX "/" CACHE PATH "Root the package layout is installed under" FORCE)
endif()
# `install` and CPack build only what the package holds (scripts/check-package.sh builds `liod`
# first), not every test and tool of the tree.
set(CMAKE_SKIP_INSTALL_ALL_DEPENDENCY ON)

# Where systemd looks, as the distribution's systemd.pc says (Debian 12: units in
# /lib/systemd/system, sysusers.d, tmpfiles.d and sysctl.d under /usr/lib); these defaults where
# it is absent. Made relative to the root so that a prefix applies.
function(liod_systemd_dir out variable fallback)
  set(dir "${fallback}")
  if(PKG_CONFIG_FOUND)
    pkg_get_variable(found systemd ${variable})
    if(found)
      set(dir "${found}")
    endif()
  endif()
  string(REGEX REPLACE "^/+" "" dir "${dir}")
  set(${out} "${dir}" PARENT_SCOPE)
endfunction()
liod_systemd_dir(LIOD_UNIT_DIR systemdsystemunitdir /lib/systemd/system)
liod_systemd_dir(LIOD_SYSUSERS_DIR sysusersdir /usr/lib/sysusers.d)
liod_systemd_dir(LIOD_TMPFILES_DIR tmpfilesdir /usr/lib/tmpfiles.d)
liod_systemd_dir(LIOD_SYSCTL_DIR sysctldir /usr/lib/sysctl.d)

set(LIOD_DOC_DIR usr/share/doc/liod)
install(TARGETS liod RUNTIME DESTINATION usr/bin COMPONENT liod)
install(FILES config/liod.yaml DESTINATION etc/liod COMPONENT liod)
install(FILES systemd/liod.service DESTINATION ${LIOD_UNIT_DIR} COMPONENT liod)
install(FILES packaging/liod.sysusers DESTINATION ${LIOD_SYSUSERS_DIR} RENAME liod.conf COMPONENT liod)
install(FILES packaging/liod.tmpfiles DESTINATION ${LIOD_TMPFILES_DIR} RENAME liod.conf COMPONENT liod)
install(FILES packaging/60-liod.conf DESTINATION ${LIOD_SYSCTL_DIR} COMPONENT liod)
install(FILES README.md docs/pose-protocol.md docs/design.md docs/backend.md docs/robustness.md docs/results.md
        DESTINATION ${LIOD_DOC_DIR} COMPONENT liod)
install(FILES config/examples/advanced.yaml config/examples/slam.yaml DESTINATION ${LIOD_DOC_DIR}/config COMPONENT liod)
# The pose socket's clients (docs/pose-protocol.md, "Clients").
install(FILES clients/c/liod_pose.h DESTINATION usr/include/liod COMPONENT liod)
install(FILES clients/python/liod_pose.py DESTINATION usr/lib/python3/dist-packages COMPONENT liod)
install(FILES clients/c/example_print_poses.c clients/python/example_print_poses.py clients/python/example_log_csv.py
        DESTINATION ${LIOD_DOC_DIR}/examples COMPONENT liod)

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME liod)
set(CPACK_PACKAGE_VENDOR "liod")
set(CPACK_PACKAGE_CONTACT "liod maintainers <liod@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGE_DIRECTORY "${CMAKE_BINARY_DIR}/package")
set(CPACK_INSTALL_CMAKE_PROJECTS "${CMAKE_BINARY_DIR};liod;liod;/")
set(CPACK_PACKAGING_INSTALL_PREFIX "/")
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION "${PROJECT_DESCRIPTION}
 A real-time LiDAR-inertial odometry and SLAM daemon for an RS-Helios LiDAR and an
 IMU, run by systemd (liod.service), publishing poses on a Unix socket. Includes a
 C header and a Python module for reading the pose socket.")
# The shared libraries the binary links (yaml-cpp, spdlog, fmt, systemd, gpiod, the bag chunks'
# bzip2, LZ4, Zstandard and zlib, and Ceres's glog, SuiteSparse and LAPACK/BLAS; the binary needs
# no libceres), from dpkg-shlibdeps; where it is missing, this list of Debian 12's packages of them.
# A cross build (cmake/aarch64-linux-gnu.cmake) takes the list: dpkg-shlibdeps looks the libraries
# up in the host's dpkg database, which holds no arm64 ones (scripts/arm64.sh checks the list
# against the arm64 binary's NEEDED entries instead).
find_program(LIOD_DPKG_SHLIBDEPS dpkg-shlibdeps)
if(LIOD_DPKG_SHLIBDEPS AND NOT CMAKE_CROSSCOMPILING)
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
else()
  set(CPACK_DEBIAN_PACKAGE_DEPENDS
      "libc6, libstdc++6, libgcc-s1, libyaml-cpp0.7, libspdlog1.10, libfmt9, libsystemd0, libgpiod2, libbz2-1.0, liblz4-1, libzstd1, zlib1g, libgoogle-glog0v6, libcholmod3, libcxsparse3, liblapack3, libatlas3-base | libblas3")
endif()
# CPack asks `dpkg --print-architecture`, the host's; a cross build names the target's.
if(CMAKE_CROSSCOMPILING AND CMAKE_SYSTEM_PROCESSOR MATCHES "^(aarch64|arm64)$")
  set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE arm64)
endif()
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "systemd")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "python3")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    "${CMAKE_SOURCE_DIR}/packaging/debian/conffiles;${CMAKE_SOURCE_DIR}/packaging/debian/postinst;${CMAKE_SOURCE_DIR}/packaging/debian/prerm;${CMAKE_SOURCE_DIR}/packaging/debian/postrm")
# Maintainer scripts 0755 and conffiles 0644 whatever the checkout's modes (Debian Policy 10.9).
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)

include(CPack)
