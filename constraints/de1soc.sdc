# Timing constraints for de1soc_top on the DE1-SoC.
create_clock -name clk -period 20.000 [get_ports {clk}]
derive_clock_uncertainty
# Asynchronous inputs: the reset button and the UART line pass two-flop synchronizers.
set_false_path -from [get_ports {rst_n rx}]
# Outputs drive stepper drivers, a laser, LEDs and displays: microsecond timing, no I/O timing
# requirement beyond the clock domain.
set_false_path -to [get_ports {tx step_x dir_x step_y dir_y laser LEDR[*] HEX0[*] HEX1[*] HEX2[*] HEX3[*] HEX4[*] HEX5[*]}]
