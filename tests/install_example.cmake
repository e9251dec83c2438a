# Installs the build into a fresh prefix, then configures, builds and runs
# examples/ against the installed package alone (find_package(radmesh)).
# Fails when any step fails or the example's output lacks what it promises.
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
function(step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

step(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(f lib/libradmesh.a bin/radmesh include/radmesh/radmesh.h include/radmesh/method.h include/radmesh/version.h
          lib/cmake/radmesh/radmeshConfig.cmake)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${prefix}/${f}")
  endif()
endforeach()
# Nothing private or heavy in the installed headers: of the third-party
# headers only GLM's, whose vectors are radmesh's Vec3 and Rgb.
file(GLOB_RECURSE headers ${prefix}/include/radmesh/*.h)
foreach(h ${headers})
  file(STRINGS ${h} bad REGEX "#include *<(CGAL|embree|vtk|X11|nlohmann|tbb|oneapi|assimp|tiny_obj|CLI|polyclipping)")
  if(bad)
    message(FATAL_ERROR "${h} includes a private dependency: ${bad}")
  endif()
endforeach()

step(${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples -B ${WORK_DIR}/build -DCMAKE_PREFIX_PATH=${prefix}
     -DCMAKE_BUILD_TYPE=Release)
step(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
step(${WORK_DIR}/build/solve_scene ${SCENE} ${WORK_DIR}/out)
message(STATUS "example output:\n${step_output}")
foreach(f radiosity.vtu summary.json)
  if(NOT EXISTS ${WORK_DIR}/out/${f})
    message(FATAL_ERROR "the example wrote no ${f}")
  endif()
endforeach()
# Every patch of the Cornell box is printed with its mean radiosity.
string(REGEX MATCHALL "\n[a-z_]+ +[0-9.e+-]+ [0-9.e+-]+ [0-9.e+-]+" rows "\n${step_output}")
list(LENGTH rows n)
if(NOT n EQUAL 21)
  message(FATAL_ERROR "expected 21 patch rows from the example, got ${n}")
endif()

# The Python module, where it was built: imported from the prefix alone,
# it solves and writes (its VTK part, _files, included).
if(PYTHON)
  set(ENV{PYTHONPATH} ${prefix}/${PYTHON_DIR})
  # (No ';' in the code: CMake would split the argument there.)
  step(${PYTHON} -c "import radmesh, sys
assert radmesh.__file__.startswith(sys.argv[2]), radmesh.__file__
r = radmesh.solve(radmesh.read_scene(sys.argv[1]), method='matrix', max_edge=300.0)
print(len(r.write(sys.argv[3], png=False)), 'files')" ${SCENE} ${prefix} ${WORK_DIR}/python_out)
  if(NOT EXISTS ${WORK_DIR}/python_out/radiosity.vtu)
    message(FATAL_ERROR "the installed Python module wrote no radiosity.vtu")
  endif()
endif()
