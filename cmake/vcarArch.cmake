include(CheckCXXCompilerFlag)
include(CheckCXXSourceRuns)
# Chooses the instruction set of the project's own binaries (tests, examples, benchmarks).
# xsimd picks its batch width from the compiler's target flags, and include/vcar/core/simd.hpp
# is the only header that looks at them: the flag is the only switch. VCAR_ARCH (CMakeLists.txt):
#   auto      x86-64: AVX-512 (-march=x86-64-v4) when the build machine runs it, else AVX2+FMA
#             when it runs them, else the compiler's default; other targets: the compiler's default
#   portable  the compiler's default (x86-64: SSE2, aarch64: NEON)
#   avx2      -mavx2 -mfma
#   other     -march=<value>: x86-64, x86-64-v2, x86-64-v3, x86-64-v4, native, armv8-a, ...
function(vcar_arch_flags target)
  set(flags "")
  if(VCAR_ARCH STREQUAL "avx2")
    set(flags -mavx2 -mfma)
  elseif(VCAR_ARCH STREQUAL "auto")
    # The widest of AVX-512 (x86-64-v4: F, BW, DQ, VL) and AVX2+FMA that both the compiler and
    # the build machine's CPU have; measured gains of v4 over AVX2 on an AVX-512 CPU are in
    # docs/embedding.md ("Compile flags for speed").
    if(NOT CMAKE_CROSSCOMPILING AND CMAKE_SYSTEM_PROCESSOR MATCHES "x86_64|AMD64|amd64")
      check_cxx_compiler_flag("-march=x86-64-v4" VCAR_HAS_V4_FLAG)
      if(VCAR_HAS_V4_FLAG)
        set(CMAKE_REQUIRED_FLAGS "-march=x86-64-v4")
        check_cxx_source_runs("
          int main() {
            return __builtin_cpu_supports(\"avx512f\") && __builtin_cpu_supports(\"avx512bw\") &&
                   __builtin_cpu_supports(\"avx512dq\") && __builtin_cpu_supports(\"avx512vl\") &&
                   __builtin_cpu_supports(\"avx2\") && __builtin_cpu_supports(\"fma\") ? 0 : 1; }"
          VCAR_CPU_HAS_V4)
        unset(CMAKE_REQUIRED_FLAGS)
      endif()
      check_cxx_compiler_flag("-mavx2 -mfma" VCAR_HAS_AVX2_FLAG)
      if(VCAR_HAS_AVX2_FLAG)
        set(CMAKE_REQUIRED_FLAGS "-mavx2 -mfma")
        check_cxx_source_runs("
          #include <immintrin.h>
          int main() { return __builtin_cpu_supports(\"avx2\") && __builtin_cpu_supports(\"fma\") ? 0 : 1; }"
          VCAR_CPU_HAS_AVX2)
        unset(CMAKE_REQUIRED_FLAGS)
      endif()
      if(VCAR_CPU_HAS_V4)
        set(flags -march=x86-64-v4)
      elseif(VCAR_CPU_HAS_AVX2)
        set(flags -mavx2 -mfma)
      endif()
    endif()
  elseif(NOT VCAR_ARCH STREQUAL "portable")
    string(MAKE_C_IDENTIFIER "VCAR_MARCH_${VCAR_ARCH}" flag_var)
    check_cxx_compiler_flag("-march=${VCAR_ARCH}" ${flag_var})
    if(NOT ${flag_var})
      message(FATAL_ERROR "vcar: VCAR_ARCH=${VCAR_ARCH}: the compiler rejects -march=${VCAR_ARCH}")
    endif()
    set(flags -march=${VCAR_ARCH})
  endif()
  message(STATUS "vcar: architecture '${VCAR_ARCH}' -> flags '${flags}'")
  target_compile_options(${target} INTERFACE ${flags})
  target_compile_options(${target} INTERFACE -Wall -Wextra)
endfunction()
