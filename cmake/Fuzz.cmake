# LIOD_FUZZ: the libFuzzer targets in fuzz/ (clang only). Every library they link is compiled with
# coverage instrumentation and ASan + UBSan, so a fuzz run exercises and checks the very code the
# daemon runs; -O1 and line tables keep the build quick and the stack traces readable.
if(LIOD_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "LIOD_FUZZ needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++")
  endif()
  if(LIOD_SANITIZE)
    message(FATAL_ERROR "LIOD_FUZZ brings its own sanitizers: leave LIOD_SANITIZE empty")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all
                      -fno-omit-frame-pointer -O1 -gline-tables-only)
  add_link_options(-fsanitize=address,undefined)
endif()
