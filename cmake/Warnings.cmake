# Warnings on for the project's own targets; third-party headers come in as SYSTEM.
add_library(liod_warnings INTERFACE)
target_compile_options(liod_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wcast-align -Wunused
  -Woverloaded-virtual -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough)

if(LIOD_SANITIZE)
  string(REPLACE ";" "," _liod_san "${LIOD_SANITIZE}")
  add_compile_options(-fsanitize=${_liod_san} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=${_liod_san})
endif()
