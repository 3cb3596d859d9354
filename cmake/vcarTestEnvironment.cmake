# Read by ctest (TEST_INCLUDE_FILES of the top directory, CMakeLists.txt): the environment every
# test inherits, unless the caller set it.
#
# OMP_WAIT_POLICY=PASSIVE: libgomp's idle threads otherwise spin between parallel regions, and
# with `ctest -j N` on N cores each test's spinning threads take the cores the other tests need:
# on 2 cores the Release suite took 164 s of wall time and 303 s of CPU time with the default
# policy, 116 s and 204 s with this one (docs/notes/build-time.md, fifth round).
if(NOT DEFINED ENV{OMP_WAIT_POLICY})
  set(ENV{OMP_WAIT_POLICY} PASSIVE)
endif()
