# One test executable per module, from tests/<module>/*.cpp:
#   test_<module>      unit/property tests, native and WASM (files not starting with ref_)
#   test_<module>_ref  cross-checks against numpy/scipy scripts run at test time (ref_*.cpp), native
# Python-driven end-to-end checks of the CLI: tests/cli/test_*.py, each gets the hawor binary.
# Longest compiles first (slam, hand), so that on two cores they do not end the build alone.
foreach(module slam hand geometry motion eval io render synth scale)
  file(GLOB _all CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/${module}/*.cpp")
  set(_unit "")
  set(_ref "")
  foreach(f ${_all})
    get_filename_component(_n "${f}" NAME)
    if(_n MATCHES "^amx_")
      continue()  # the AMX target below
    elseif(_n MATCHES "^ref_")
      list(APPEND _ref "${f}")
    else()
      list(APPEND _unit "${f}")
    endif()
  endforeach()
  # The sanitizer build (HAWOR_SANITIZE) compiles only the tests of file parsers: all of io/,
  # and the pickle / glTF / model-file tests of hand/ (keeps that Debug+ASan build short).
  set(_parser "")
  if(module STREQUAL "io" OR module STREQUAL "hand")
    set(_parser PARSER)
  endif()
  # The WebAssembly build leaves out the synthetic generator's tests (the generator is not part
  # of the WebAssembly core: wasm/bindings.cpp does not include synth/), and those of hand/,
  # motion/ and slam/, whose WebAssembly paths run end to end in the core's own tests: the fit
  # against a known pose, the default and MANO-format hand models and the infilling in
  # wasm_bindings (tests/wasm/test_bindings.mjs), MonoSlam there against the ground truth and the
  # native CLI, the whole pipeline (SLAM, fit, masks, scale, infilling) in
  # tests/web/pipeline_native_wasm.test.mjs against the native build to 1e-14 m, the MANO
  # pickles dropped on the page in tests/browser. The four were about four minutes of the suite's
  # two cores (slam/'s unit alone 80 s), which ran at its 15-minute budget; render/ (masks,
  # rectification, resampling), geometry/, scale/, eval/ and io/ keep their WebAssembly unit tests.
  if(EMSCRIPTEN AND module MATCHES "^(synth|hand|motion|slam)$")
    set(_unit "")
  endif()
  if(HAWOR_SANITIZE AND module STREQUAL "hand")
    list(FILTER _unit INCLUDE REGEX "(pickle|gltf|mano_loader|model_io)[^/]*\\.cpp$")
  endif()
  # Modules whose tests run in seconds unoptimised (natively and under node) build at -O0.
  set(_unit_opt "")
  set(_ref_opt "")
  if(module MATCHES "^(geometry|eval|io)$")
    set(_unit_opt UNOPTIMISED)
    set(_ref_opt UNOPTIMISED)
  elseif(module STREQUAL "hand")
    set(_ref_opt UNOPTIMISED)
  endif()
  if(_unit)
    hawor_add_test(test_${module} SOURCES ${_unit} ${_parser} ${_unit_opt} LABELS ${module})
  endif()
  if(_ref)
    hawor_add_test(test_${module}_ref SOURCES ${_ref} NATIVE_ONLY ${_ref_opt} LABELS ${module} ref)
  endif()
endforeach()

# test_motion_amx: tests/motion/amx_*.cpp, the AMX backend of matmul.hpp and the infiller on it,
# compiled with -mamx-tile -mamx-bf16 (the rest of the suite keeps the portable flags) where the
# compiler has them, natively. Only the AMX flags: the binary runs on any x86-64 CPU and its
# cases skip (a WARN) where the CPU or the kernel do not allow AMX. Two entries: the unit cases,
# and the onnxruntime cross-check (label ref, needs node).
if(NOT EMSCRIPTEN AND NOT HAWOR_SANITIZE)
  include(CheckCXXCompilerFlag)
  check_cxx_compiler_flag("-mamx-tile -mamx-bf16" HAWOR_HAS_AMX_FLAGS)
  file(GLOB _amx CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/motion/amx_*.cpp")
  if(HAWOR_HAS_AMX_FLAGS AND _amx)
    add_executable(test_motion_amx ${_amx})
    target_link_libraries(test_motion_amx PRIVATE hawor::hawor hawor_stb hawor_catch_main)
    target_compile_definitions(test_motion_amx PRIVATE
      HAWOR_SOURCE_DIR="${PROJECT_SOURCE_DIR}" HAWOR_REF_DIR="${HAWOR_REF_DIR}"
      HAWOR_PYTHON="${HAWOR_PYTHON}")
    target_compile_options(test_motion_amx PRIVATE -O1 -mamx-tile -mamx-bf16)
    add_test(NAME test_motion_amx COMMAND test_motion_amx "~[ref]")
    set_tests_properties(test_motion_amx PROPERTIES LABELS "native;motion;amx")
    add_test(NAME test_motion_amx_ref COMMAND test_motion_amx "[ref]")
    set_tests_properties(test_motion_amx_ref PROPERTIES LABELS "native;motion;amx;ref")
  endif()
endif()

if(HAWOR_BUILD_EXAMPLES AND NOT EMSCRIPTEN AND NOT HAWOR_SANITIZE)
  file(GLOB _cli_tests CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/cli/test_*.py")
  foreach(f ${_cli_tests})
    get_filename_component(_n "${f}" NAME_WE)
    add_test(NAME cli_${_n} COMMAND ${HAWOR_PYTHON} "${f}" $<TARGET_FILE:hawor_cli>)
    set_tests_properties(cli_${_n} PROPERTIES LABELS "native;cli;python")
  endforeach()
endif()
