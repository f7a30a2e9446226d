# Read by ctest after the tests discovered in the test binaries (TEST_INCLUDE_FILES). The longest tests are given
# their cost, so that ctest starts them first: on a fresh build there is no cost data yet, and ctest would run them
# in their numbering, the GPU tests and the packaging tests last, one core left waiting on them. Costs in
# seconds of one Release run on two cores (`ctest --test-dir build -j 2`); only their order matters. A test renamed
# or removed is passed over.
set(_drape_costs  # the start of each test's name, and its cost
  "the rigid rain on the GPU keeps the CPU's invariants over 2 s" 268
  "a cloth dropped on meshed solids (grid fields): GPU and CPU agree" 171
  "a cloth folded into a V gutter of two planes: the GPU solver" 44
  "sliding down the slope, the GPU solver's cloth has the CPU's trembling" 32
  "a cloth dropped on a box, a capsule, a cylinder or a hull: GPU and CPU" 28
  "coupling on the GPU: a ball hitting a free cloth keeps the total momentum" 22
  "faces: a cloth resting on a floor or sliding down a slope does not tremble nor penetrate - double" 22
  "coupling on the GPU: a box resting on a cloth on the ground gets its weight back" 21
  "two GPU runs of a coupled scene are bit-identical" 19
  "faces: a cloth resting on a floor or sliding down a slope does not tremble nor penetrate - float" 13)
list(LENGTH _drape_costs _drape_n)
math(EXPR _drape_last "${_drape_n} - 1")
foreach(_drape_test IN LISTS drape_tests_TESTS drape_gpu_tests_TESTS)
  foreach(_drape_i RANGE 0 ${_drape_last} 2)
    list(GET _drape_costs ${_drape_i} _drape_start)
    string(FIND "${_drape_test}" "${_drape_start}" _drape_at)
    if(_drape_at EQUAL 0)
      math(EXPR _drape_j "${_drape_i} + 1")
      list(GET _drape_costs ${_drape_j} _drape_cost)
      set_tests_properties("${_drape_test}" PROPERTIES COST ${_drape_cost})
      break()
    endif()
  endforeach()
endforeach()
