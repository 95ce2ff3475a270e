phaco_test(test_scenario SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_scenario.cpp LIBS phaco_io)
