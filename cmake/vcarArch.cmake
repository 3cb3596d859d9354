include(CheckCXXCompilerFlag)
include(CheckCXXSourceRuns)
# Chooses the SIMD architecture of the project's own binaries. xsimd picks its batch width
# from the compiler's target flags, so the flag is the only switch; algorithm code has none.
function(vcar_arch_flags target)
  set(flags "")
  if(VCAR_ARCH STREQUAL "native")
    set(flags -march=native)
  elseif(VCAR_ARCH STREQUAL "avx2")
    set(flags -mavx2 -mfma)
  elseif(VCAR_ARCH STREQUAL "auto")
    check_cxx_compiler_flag("-mavx2 -mfma" VCAR_HAS_AVX2_FLAG)
    if(VCAR_HAS_AVX2_FLAG)
      set(CMAKE_REQUIRED_FLAGS "-mavx2 -mfma")
      check_cxx_source_runs("
        #include <immintrin.h>
        int main() { return __builtin_cpu_supports(\"avx2\") && __builtin_cpu_supports(\"fma\") ? 0 : 1; }"
        VCAR_CPU_HAS_AVX2)
      unset(CMAKE_REQUIRED_FLAGS)
      if(VCAR_CPU_HAS_AVX2)
        set(flags -mavx2 -mfma)
      endif()
    endif()
  endif()
  message(STATUS "vcar: architecture '${VCAR_ARCH}' -> flags '${flags}'")
  target_compile_options(${target} INTERFACE ${flags})
  target_compile_options(${target} INTERFACE -Wall -Wextra)
endfunction()
