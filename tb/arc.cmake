# Circular DDA: arc_dda against the integer reference walk
# (fpgacnc/models/arc_walk.h of models/).
fpgacnc_verilated(varc TOP arc_dda SOURCES ${FPGACNC_RTL_DIR}/motion/arc_dda.v)
fpgacnc_bench(test_arc_dda LABEL rtl SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_arc_dda.cpp
              LIBS varc fmt::fmt)
# ARC frames through cnc_core's pins (decoder -> FIFO -> prep -> executor -> arc_dda)
fpgacnc_bench(test_arc_core LABEL rtl SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_arc_core.cpp
              LIBS vcore_heat fmt::fmt)
