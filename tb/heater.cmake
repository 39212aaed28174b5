# Heater benches (docs/heater.md): unit benches of pwm, pid_incr, ltc2308_spi, temp_table, and the
# heater_block benches (safety faults, closed-loop bed and hot end against the plant models).
fpgacnc_verilated(vpwm TOP pwm SOURCES ${FPGACNC_RTL_DIR}/machine/pwm.v ARGS -GPWM_BITS=4 -GPWM_DIV=3)
fpgacnc_verilated(vpid TOP pid_incr SOURCES ${FPGACNC_RTL_DIR}/heater/pid_incr.v)
fpgacnc_verilated(vadc TOP ltc2308_spi SOURCES ${FPGACNC_RTL_DIR}/heater/ltc2308_spi.v)
fpgacnc_verilated(vtable TOP temp_table SOURCES ${FPGACNC_RTL_DIR}/heater/temp_table.v)
# Scaled time: one sample tick every 4096 clocks, PWM period 1024 clocks (4 per tick).
fpgacnc_verilated(vheat TOP heater_block SOURCES ${FPGACNC_HEATER_RTL}
                  ARGS -GSAMPLE_CLKS=${FPGACNC_SPEC_BENCH_SAMPLE_CLKS} -GPWM_DIV=1)

fpgacnc_bench(test_heater_units LABEL rtl
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_heater_units.cpp LIBS vpwm vpid vadc vtable)
fpgacnc_bench(test_heater_block LABEL rtl
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_heater_block.cpp LIBS vheat)
# vcore_heat (tb/core.cmake): cnc_core with heaters at 3 Mbaud, scaled sample tick and PWM.
fpgacnc_bench(test_heater_core LABEL system
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_heater_core.cpp LIBS vcore_heat)
