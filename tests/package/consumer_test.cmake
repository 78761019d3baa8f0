# SPDX-License-Identifier: MIT
# Installs the build tree into a scratch prefix, then configures, builds and runs
# examples/consumer against it as a project outside the tree would:
#   cmake -DSOURCE=... -DBUILD=... -DCOMPILER=... [-DLAUNCHER=...] -P consumer_test.cmake
# With -DSHARED_CACHE=FILE it installs instead a shared build of the library and the program
# alone (BUILD_SHARED_LIBS), configured from SOURCE with FILE as its initial cache.
if(SHARED_CACHE)
  set(work ${BUILD}/package_test_shared)
else()
  set(work ${BUILD}/package_test)
endif()
set(prefix ${work}/prefix)
set(consumer ${work}/consumer)
file(REMOVE_RECURSE ${work})

function(step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "${what} failed (${code}):\n${out}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

set(installed include/nfield/fields/field.h include/nfield/autodiff/streams.h
    include/nfield/solvers/run/run.h include/nfield/io/config.h bin/nfield
    lib/cmake/nfield/nfieldConfig.cmake lib/cmake/nfield/nfieldConfigVersion.cmake)
if(SHARED_CACHE)
  set(library ${work}/library)
  step("configuring the shared library"
       ${CMAKE_COMMAND} -C ${SHARED_CACHE} -S ${SOURCE} -B ${library})
  step("building the shared library" ${CMAKE_COMMAND} --build ${library} --parallel 2)
  step("cmake --install" ${CMAKE_COMMAND} --install ${library} --prefix ${prefix})
  file(GLOB_RECURSE libraries RELATIVE ${prefix} ${prefix}/lib*/libnfield*)
  if(NOT libraries MATCHES "libnfield\\.so" OR libraries MATCHES "libnfield\\.a")
    message(FATAL_ERROR "the install holds ${libraries}, not one shared libnfield.so")
  endif()
  # The installed program finds the installed library (its install RPATH), no LD_LIBRARY_PATH.
  step("running the installed program" ${prefix}/bin/nfield --version)
else()
  step("cmake --install" ${CMAKE_COMMAND} --install ${BUILD} --prefix ${prefix})
endif()
foreach(file IN LISTS installed)
  if(NOT EXISTS ${prefix}/${file})
    message(FATAL_ERROR "the install lacks ${file}")
  endif()
endforeach()

set(configure ${CMAKE_COMMAND} -S ${SOURCE}/examples/consumer -B ${consumer}
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${COMPILER}
    -DCMAKE_EXPORT_COMPILE_COMMANDS=ON)
if(LAUNCHER)
  list(APPEND configure -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
step("configuring the consumer" ${configure})
# The consumer's project enables C++ alone: finding the package must not need a C compiler.
file(GLOB c_compiler ${consumer}/CMakeFiles/*/CMakeCCompiler.cmake)
if(c_compiler)
  message(FATAL_ERROR "the consumer enabled C: ${c_compiler}")
endif()
step("building the consumer" ${CMAKE_COMMAND} --build ${consumer} --parallel 2)

# What the package hands a consumer: the prefix's headers, not the source tree's, and no
# -march=native unless it links nfield::native.
file(READ ${consumer}/compile_commands.json commands)
if(commands MATCHES "-march=native")
  message(FATAL_ERROR "-march=native reached the consumer:\n${commands}")
endif()
string(FIND "${commands}" "${prefix}/include/nfield" at)
if(at EQUAL -1)
  message(FATAL_ERROR "the consumer does not include from ${prefix}/include/nfield:\n${commands}")
endif()
string(FIND "${commands}" "-I${SOURCE} " at)
string(FIND "${commands}" "-isystem ${SOURCE} " at_system)
if(NOT at EQUAL -1 OR NOT at_system EQUAL -1)
  message(FATAL_ERROR "the consumer includes from the source tree:\n${commands}")
endif()

if(SHARED_CACHE)
  file(READ ${consumer}/CMakeFiles/consumer.dir/link.txt link)
  string(FIND "${link}" "${prefix}/lib" at)
  if(at EQUAL -1 OR NOT link MATCHES "libnfield\\.so")
    message(FATAL_ERROR "the consumer does not link ${prefix}'s libnfield.so:\n${link}")
  endif()
endif()

step("running the consumer" ${consumer}/consumer)
message("${step_output}")
if(NOT step_output MATCHES "consumer: ok")
  message(FATAL_ERROR "the consumer did not report ok")
endif()
