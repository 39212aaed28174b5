# Homing and probing through cnc_core's pins (docs/machine.md "Homing and probing (hardware)"):
# the DE1-SoC core's configuration (full-2axis) at 3 Mbaud, its four limit switches enabled
# (bits 0, 1 min, 16, 17 max, active high), a 500-clock switch debounce, the probe wired (active
# high) with a 200-clock debounce.
fpgacnc_verilated(vcore_trigger TOP cnc_core PREFIX Vcnc_core_trigger CONFIG full-2axis
                  SOURCES ${FPGACNC_CORE_RTL}
                  ARGS -GBAUD=3000000 -GLIMIT_FILTER_CLKS=500 -GLIMIT_ENABLE=196611
                       -GPROBE_ENABLE=1 -GPROBE_FILTER_CLKS=200)
fpgacnc_bench(test_trigger LABEL system SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_trigger.cpp
              LIBS vcore_trigger fmt::fmt)
