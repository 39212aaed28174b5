# Circular DDA: arc_dda against the integer reference walk
# (systemc/include/fpgacnc/twins/arc_walk.h, header-only, no SystemC).
fpgacnc_verilated(varc TOP arc_dda SOURCES ${FPGACNC_RTL_DIR}/arc_dda.v)
fpgacnc_bench(test_arc_dda LABEL rtl SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_arc_dda.cpp
              LIBS varc fmt::fmt)
target_include_directories(test_arc_dda PRIVATE ${PROJECT_SOURCE_DIR}/systemc/include)
# ARC frames through cnc_core's pins (decoder -> FIFO -> prep -> executor -> arc_dda)
fpgacnc_bench(test_arc_core LABEL rtl SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_arc_core.cpp
              LIBS vcore_3m fmt::fmt)
target_include_directories(test_arc_core PRIVATE ${PROJECT_SOURCE_DIR}/systemc/include)
