# Sourced by scripts/test.sh and scripts/demo.sh: the compiler of build/native, the same for both
# so that they share one CMake cache. clang++ when installed (faster compiles of the template-heavy
# code), else the system default; HAWOR_NATIVE_CXX overrides (e.g. HAWOR_NATIVE_CXX=g++).
native_compiler_env() {
  local cxx=${HAWOR_NATIVE_CXX:-}
  if [[ -z "$cxx" ]] && command -v clang++ >/dev/null; then cxx=clang++; fi
  [[ -n "$cxx" ]] || return 0
  local cc=${cxx/clang++/clang}; cc=${cc/g++/gcc}
  echo "CC=$cc CXX=$cxx"
}
