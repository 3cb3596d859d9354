# Installs vcar into a scratch prefix, then builds and runs consumers of the installed tree:
# 1. vcar::vcar alone with find_package(vcar CONFIG REQUIRED), nlohmann_json's package made
#    unfindable and nlohmann's and stb's headers hidden behind #error stand-ins (poison/);
# 2. the same umbrella's `-M` (every header it reaches) must name neither nlohmann nor stb;
# 3. vcar::io through find_package(vcar COMPONENTS io);
# 4. Makefile-style hosts: `pkg-config --cflags vcar` and `pkg-config --cflags --libs vcar-io`.
# Arguments: VCAR_SOURCE_DIR, WORK_DIR, CXX (the compiler of the main build).
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
set(project_dir ${VCAR_SOURCE_DIR}/tests/consumer/project)
function(run)
  execute_process(COMMAND ${ARGV} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGV}")
  endif()
endfunction()
run(${CMAKE_COMMAND} -S ${VCAR_SOURCE_DIR} -B ${WORK_DIR}/vcar-build -DVCAR_BUILD_TESTS=OFF
    -DVCAR_BUILD_EXAMPLES=OFF -DVCAR_BUILD_BENCHMARKS=OFF -DCMAKE_INSTALL_PREFIX=${prefix})
run(${CMAKE_COMMAND} --install ${WORK_DIR}/vcar-build)

# 1. vcar::vcar alone, io's dependencies out of reach.
run(${CMAKE_COMMAND} -S ${project_dir} -B ${WORK_DIR}/consumer-build
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release -DCONSUMER_VCAR_ONLY=ON
    -DCMAKE_DISABLE_FIND_PACKAGE_nlohmann_json=ON -DCMAKE_EXPORT_COMPILE_COMMANDS=ON)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/consumer-build)
run(${WORK_DIR}/consumer-build/consumer)

# 2. -M of <vcar/vcar.hpp> with the consumer's own compile command.
file(READ ${WORK_DIR}/consumer-build/compile_commands.json commands)
string(JSON command GET "${commands}" 0 command)
separate_arguments(args UNIX_COMMAND "${command}")
set(keep "")
set(skip_next OFF)
foreach(a ${args})
  if(skip_next)
    set(skip_next OFF)
  elseif(a STREQUAL "-o" OR a STREQUAL "-MT" OR a STREQUAL "-MF")
    set(skip_next ON)
  elseif(NOT a STREQUAL "-c" AND NOT a STREQUAL "-MD")
    list(APPEND keep "${a}")
  endif()
endforeach()
list(FILTER keep EXCLUDE REGEX "poison")  # the real include path, as a host would have it
execute_process(COMMAND ${keep} -M WORKING_DIRECTORY ${WORK_DIR}/consumer-build
                OUTPUT_VARIABLE deps RESULT_VARIABLE rc)
if(NOT rc EQUAL 0 OR NOT deps MATCHES "vcar/vcar\\.hpp" OR NOT deps MATCHES "vcar/algo/pipeline\\.hpp")
  message(FATAL_ERROR "-M of the umbrella failed (${rc}): ${keep}")
endif()
foreach(forbidden nlohmann stb_image opencv "vcar/io/" "vcar/synth/" "vcar/baselines/")
  string(FIND "${deps}" "${forbidden}" at)
  if(NOT at EQUAL -1)
    message(FATAL_ERROR "<vcar/vcar.hpp> reaches '${forbidden}':\n${deps}")
  endif()
endforeach()
message(STATUS "<vcar/vcar.hpp> reaches neither nlohmann nor stb")

# 3. vcar::io as a component.
run(${CMAKE_COMMAND} -S ${project_dir} -B ${WORK_DIR}/consumer-io-build
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
# (consumer_io alone: `consumer` is the same source as in 1, and vcar::io carries vcar::vcar.)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/consumer-io-build --target consumer_io)
run(${WORK_DIR}/consumer-io-build/consumer_io)

# 4. pkg-config, as a Makefile host uses it.
find_program(PKG_CONFIG pkg-config REQUIRED)
set(ENV{PKG_CONFIG_PATH} "${prefix}/share/pkgconfig")
function(pkg out)
  execute_process(COMMAND ${PKG_CONFIG} ${ARGN} OUTPUT_VARIABLE flags RESULT_VARIABLE rc OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pkg-config ${ARGN} failed")
  endif()
  separate_arguments(flags UNIX_COMMAND "${flags}")
  set(${out} ${flags} PARENT_SCOPE)
endfunction()
pkg(cflags --cflags vcar)
pkg(libs --libs vcar)
if(NOT "${cflags}" MATCHES "${prefix}/include")
  message(FATAL_ERROR "pkg-config --cflags vcar does not name the installed headers: ${cflags}")
endif()
run(${CXX} -std=c++20 -O1 -I${VCAR_SOURCE_DIR}/tests/consumer/poison ${cflags} ${project_dir}/main.cpp
    -o ${WORK_DIR}/consumer-pc ${libs})
run(${WORK_DIR}/consumer-pc)
pkg(io_cflags --cflags vcar-io)
pkg(io_libs --libs vcar-io)
run(${CXX} -std=c++20 -O1 ${io_cflags} "-DVCAR_TEST_PLY=\"${VCAR_SOURCE_DIR}/tests/data/donut.ply\""
    ${project_dir}/main_io.cpp -o ${WORK_DIR}/consumer-io-pc ${io_libs})
run(${WORK_DIR}/consumer-io-pc)
