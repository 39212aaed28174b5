# Hard limits, homing and probing through cnc_core's pins (docs/machine.md): one model for
# test_limits and test_trigger (tb/trigger.cmake), the DE1-SoC core's configuration (full-2axis)
# at 3 Mbaud with its four limit switches enabled (bits 0, 1 min, 16, 17 max), X min active low,
# a 500-clock switch debounce, the probe wired (active high) with a 200-clock debounce.
fpgacnc_verilated(vcore_machine TOP cnc_core PREFIX Vcnc_core_machine CONFIG full-2axis
                  SOURCES ${FPGACNC_CORE_RTL}
                  ARGS -GBAUD=3000000 -GLIMIT_FILTER_CLKS=500 -GLIMIT_ENABLE=196611
                       -GLIMIT_ACTIVE_LOW=1 -GPROBE_ENABLE=1 -GPROBE_FILTER_CLKS=200)
fpgacnc_bench(test_limits LABEL system SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_limits.cpp
              LIBS vcore_machine fpgacnc_models fmt::fmt)
