# The laser / spindle PWM through cnc_core's pins (docs/machine.md "Laser and spindle PWM"): the
# DE1-SoC core's configuration (full-2axis) at 3 Mbaud, LASER_PWM_HZ at its default.
fpgacnc_verilated(vcore_pwm TOP cnc_core PREFIX Vcnc_core_pwm CONFIG full-2axis
                  SOURCES ${FPGACNC_CORE_RTL} ARGS -GBAUD=3000000)
fpgacnc_bench(test_laser_pwm LABEL system SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_laser_pwm.cpp
              LIBS vcore_pwm fmt::fmt)
