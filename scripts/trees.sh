# The build trees scripts/test.sh and scripts/fuzz.sh share, configured in one place so that each
# script finds a tree the other built exactly as it left it (sourced, not run).
#
#   configure_tree release|asan|tsan DIR
#
#   release  gcc, Release (-O3): what ships; tests, tools and benchmarks.
#   asan     clang, AddressSanitizer + UndefinedBehaviorSanitizer, and the libFuzzer targets
#            (LIOD_FUZZ): the tests and the fuzzers share one build of the libraries.
#   tsan     clang, ThreadSanitizer.
#   (Both build C, the pose client example in clients/, with clang too.)
#
# The sanitizer trees are built by clang at -O2 with line tables (-g1, enough for the reports'
# stack traces): clang compiles the Eigen-heavy units under ASan + UBSan in about half gcc's time,
# and at -O2 in about the time of -O1 while the tests then run faster. Ninja, when present, starts
# a target's compiles before the libraries it links are archived, which keeps both cores busy.

sanitizer_flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG")

configure_tree() {
  local kind=$1 dir=$2
  local args=(-S . -B "$dir")
  # An existing tree keeps its generator (CMake refuses to switch one).
  if [ ! -f "$dir/CMakeCache.txt" ] && command -v ninja >/dev/null; then args+=(-G Ninja); fi
  case "$kind" in
    release) args+=(-DCMAKE_BUILD_TYPE=Release) ;;
    asan) args+=(-DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang "${sanitizer_flags[@]}" "-DLIOD_SANITIZE=address;undefined" -DLIOD_FUZZ=ON) ;;
    tsan) args+=(-DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang "${sanitizer_flags[@]}" -DLIOD_SANITIZE=thread) ;;
    *) echo "configure_tree: unknown tree '$kind'" >&2; return 1 ;;
  esac
  cmake "${args[@]}" >/dev/null
}
