# Every dependency is found through its own CMake config (Debian packages in brackets).
find_package(Eigen3 3.4 REQUIRED NO_MODULE)          # libeigen3-dev
if(VCAR_SIMD)
  find_package(xtl QUIET)                             # xtl-dev: xsimd 8's exported target links it
  find_package(xsimd 8 REQUIRED)                      # libxsimd-dev
endif()
if(VCAR_USE_OPENMP)
  find_package(OpenMP COMPONENTS CXX)                 # optional: serial and identical without
endif()
if(VCAR_WITH_IO)                                      # vcar::io and vcar::synth only
  find_package(nlohmann_json 3 REQUIRED)              # nlohmann-json3-dev
  include(${CMAKE_CURRENT_LIST_DIR}/vcarStb.cmake)    # libstb-dev (pkg-config stb)
  if(NOT TARGET vcar::stb)
    message(FATAL_ERROR "vcar: stb not found (Debian: apt-get install libstb-dev), or configure with -DVCAR_WITH_IO=OFF")
  endif()
  find_package(ZLIB REQUIRED)                         # zlib1g-dev: SPZ v2/v3 (gzip)
  include(${CMAKE_CURRENT_LIST_DIR}/vcarZstd.cmake)   # libzstd-dev: SPZ v4
  if(NOT TARGET vcar::zstd)
    message(FATAL_ERROR "vcar: zstd not found (Debian: apt-get install libzstd-dev), or configure with -DVCAR_WITH_IO=OFF")
  endif()
endif()
# Optional, for vcar::baselines only:
find_package(nanoflann QUIET)                         # libnanoflann-dev
find_package(Boost 1.74 QUIET)                        # libboost-graph-dev (header-only use)
