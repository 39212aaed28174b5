# Timing constraints for de1soc_top on the DE1-SoC.
create_clock -name clk -period 20.000 [get_ports {clk}]
derive_clock_uncertainty
# Asynchronous inputs: the reset button, the UART line and the probe pass two-flop synchronizers.
set_false_path -from [get_ports {rst_n rx estop_n hold_n start_n probe_n ADC_SDO}]
# estop_n and ADC_SDO also pass two-flop synchronizers; the LTC2308 master (rtl/heater/ltc2308_spi.v)
# samples the synchronized SDO SCK_DIV (5) clocks after the chip shifts it, so no I/O timing on it.
# Outputs drive stepper drivers, a laser, LEDs and displays: microsecond timing, no I/O timing
# requirement beyond the clock domain.
set_false_path -to [get_ports {tx step_x dir_x step_y dir_y laser LEDR[*] HEX0[*] HEX1[*] HEX2[*] HEX3[*] HEX4[*] HEX5[*]}]
# Heater MOSFET gates (PWM at ~10 Hz) and the ADC's CONVST/SCK/SDI: registered outputs changing at
# most every SCK_DIV (5) clocks (SCK 5 MHz), far slower than any I/O delay.
set_false_path -to [get_ports {heater_hotend heater_bed ADC_CONVST ADC_SCK ADC_SDI}]
# Machine outputs (coolant valves, part-cooling fan PWM at ~1 kHz, digital outputs): drivers
# switching in microseconds or slower, no I/O timing requirement beyond the clock domain.
set_false_path -to [get_ports {coolant_flood coolant_mist fan dout[*]}]
