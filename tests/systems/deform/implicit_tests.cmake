# Implicit Euler and the seed-004 predictor (systems/deform/implicit*.cpp); included from this
# folder's CMakeLists.txt.
phaco_test(test_implicit
  SOURCES
    ${CMAKE_CURRENT_LIST_DIR}/test_implicit.cpp
    ${CMAKE_CURRENT_LIST_DIR}/test_implicit_active.cpp
    ${CMAKE_CURRENT_LIST_DIR}/test_implicit_predictor.cpp
    ${CMAKE_CURRENT_LIST_DIR}/test_team_choice.cpp
  LIBS phaco_sys_deform phaco_sys_springs phaco_sys_active_nodes phaco_eye TBB::tbb)
# Not in unity batches (PHACO_UNITY_BUILD): its three files each define the frame step and helpers
# of the same names at file scope, as the deform library itself is kept out.
set_target_properties(test_implicit PROPERTIES UNITY_BUILD OFF)
# Implicit Euler's linear solve: operator, preconditioners, threaded product (implicit_solver.cpp).
phaco_test(test_implicit_solver
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_implicit_solver.cpp
  LIBS phaco_sys_deform phaco_sys_springs phaco_sys_active_nodes phaco_eye TBB::tbb)
