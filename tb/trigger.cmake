# Homing and probing through cnc_core's pins (docs/machine.md "Homing and probing (hardware)") on
# test_limits's model (tb/limits.cmake): full-2axis at 3 Mbaud, the four limit switches (X min
# active low), the probe with a 200-clock debounce.
fpgacnc_bench(test_trigger LABEL system SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_trigger.cpp
              LIBS vcore_machine fmt::fmt)
