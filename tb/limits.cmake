# Hard limits through cnc_core's pins (docs/machine.md): the DE1-SoC core's configuration
# (full-2axis) at 3 Mbaud with its four limit switches enabled (bits 0, 1 min, 16, 17 max), X min
# active low, a 500-clock debounce.
fpgacnc_verilated(vcore_limits TOP cnc_core PREFIX Vcnc_core_limits CONFIG full-2axis
                  SOURCES ${FPGACNC_CORE_RTL}
                  ARGS -GBAUD=3000000 -GLIMIT_FILTER_CLKS=500 -GLIMIT_ENABLE=196611
                       -GLIMIT_ACTIVE_LOW=1)
fpgacnc_bench(test_limits LABEL system SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_limits.cpp
              LIBS vcore_limits fpgacnc_models fmt::fmt)
