# DE1-SoC (5CSEMA5F31C6) pin assignments for de1soc_top.
# Original controller pins (docs/architecture.md "Pins"); LEDR and HEX pins from the Terasic DE1-SoC manual.
# All I/O 3.3-V LVTTL.

set_location_assignment PIN_AF14 -to clk
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to clk
set_location_assignment PIN_AA14 -to rst_n
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to rst_n
set_location_assignment PIN_AA15 -to hold_n
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to hold_n
set_location_assignment PIN_W15 -to start_n
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to start_n
set_location_assignment PIN_AC18 -to rx
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to rx
set_location_assignment PIN_Y17 -to tx
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to tx
set_location_assignment PIN_AD17 -to dir_x
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to dir_x
set_location_assignment PIN_Y18 -to step_x
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to step_x
set_location_assignment PIN_AK16 -to dir_y
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to dir_y
set_location_assignment PIN_AK18 -to step_y
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to step_y
set_location_assignment PIN_AK19 -to laser
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to laser
set_location_assignment PIN_V16 -to LEDR[0]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to LEDR[0]
set_location_assignment PIN_W16 -to LEDR[1]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to LEDR[1]
set_location_assignment PIN_V17 -to LEDR[2]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to LEDR[2]
set_location_assignment PIN_V18 -to LEDR[3]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to LEDR[3]
set_location_assignment PIN_W17 -to LEDR[4]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to LEDR[4]
set_location_assignment PIN_W19 -to LEDR[5]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to LEDR[5]
set_location_assignment PIN_Y19 -to LEDR[6]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to LEDR[6]
set_location_assignment PIN_W20 -to LEDR[7]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to LEDR[7]
set_location_assignment PIN_W21 -to LEDR[8]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to LEDR[8]
set_location_assignment PIN_Y21 -to LEDR[9]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to LEDR[9]
set_location_assignment PIN_AE26 -to HEX0[0]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX0[0]
set_location_assignment PIN_AE27 -to HEX0[1]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX0[1]
set_location_assignment PIN_AE28 -to HEX0[2]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX0[2]
set_location_assignment PIN_AG27 -to HEX0[3]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX0[3]
set_location_assignment PIN_AF28 -to HEX0[4]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX0[4]
set_location_assignment PIN_AG28 -to HEX0[5]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX0[5]
set_location_assignment PIN_AH28 -to HEX0[6]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX0[6]
set_location_assignment PIN_AJ29 -to HEX1[0]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX1[0]
set_location_assignment PIN_AH29 -to HEX1[1]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX1[1]
set_location_assignment PIN_AH30 -to HEX1[2]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX1[2]
set_location_assignment PIN_AG30 -to HEX1[3]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX1[3]
set_location_assignment PIN_AF29 -to HEX1[4]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX1[4]
set_location_assignment PIN_AF30 -to HEX1[5]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX1[5]
set_location_assignment PIN_AD27 -to HEX1[6]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX1[6]
set_location_assignment PIN_AB23 -to HEX2[0]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX2[0]
set_location_assignment PIN_AE29 -to HEX2[1]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX2[1]
set_location_assignment PIN_AD29 -to HEX2[2]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX2[2]
set_location_assignment PIN_AC28 -to HEX2[3]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX2[3]
set_location_assignment PIN_AD30 -to HEX2[4]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX2[4]
set_location_assignment PIN_AC29 -to HEX2[5]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX2[5]
set_location_assignment PIN_AC30 -to HEX2[6]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX2[6]
set_location_assignment PIN_AD26 -to HEX3[0]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX3[0]
set_location_assignment PIN_AC27 -to HEX3[1]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX3[1]
set_location_assignment PIN_AD25 -to HEX3[2]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX3[2]
set_location_assignment PIN_AC25 -to HEX3[3]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX3[3]
set_location_assignment PIN_AB28 -to HEX3[4]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX3[4]
set_location_assignment PIN_AB25 -to HEX3[5]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX3[5]
set_location_assignment PIN_AB22 -to HEX3[6]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX3[6]
set_location_assignment PIN_AA24 -to HEX4[0]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX4[0]
set_location_assignment PIN_Y23 -to HEX4[1]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX4[1]
set_location_assignment PIN_Y24 -to HEX4[2]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX4[2]
set_location_assignment PIN_W22 -to HEX4[3]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX4[3]
set_location_assignment PIN_W24 -to HEX4[4]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX4[4]
set_location_assignment PIN_V23 -to HEX4[5]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX4[5]
set_location_assignment PIN_W25 -to HEX4[6]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX4[6]
set_location_assignment PIN_V25 -to HEX5[0]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX5[0]
set_location_assignment PIN_AA28 -to HEX5[1]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX5[1]
set_location_assignment PIN_Y27 -to HEX5[2]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX5[2]
set_location_assignment PIN_AB27 -to HEX5[3]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX5[3]
set_location_assignment PIN_AB26 -to HEX5[4]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX5[4]
set_location_assignment PIN_AA26 -to HEX5[5]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX5[5]
set_location_assignment PIN_AA25 -to HEX5[6]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to HEX5[6]

# Heaters and e-stop (docs/heater.md): GPIO_0[7..9] (pins from the Terasic DE1-SoC
# manual). heater_* drive MOSFET gate drivers; estop_n is active low (normally-closed switch to
# ground), with the weak pull-up on so that an open wire reads as "stop".
set_location_assignment PIN_AJ19 -to heater_hotend
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to heater_hotend
set_location_assignment PIN_AJ17 -to heater_bed
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to heater_bed
set_location_assignment PIN_AJ16 -to estop_n
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to estop_n
set_instance_assignment -name WEAK_PULL_UP_RESISTOR ON -to estop_n
# On-board LTC2308 ADC (DE1-SoC dedicated pins; the manual calls SDI/SDO ADC_DIN/ADC_DOUT).
set_location_assignment PIN_AJ4 -to ADC_CONVST
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to ADC_CONVST
set_location_assignment PIN_AK2 -to ADC_SCK
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to ADC_SCK
set_location_assignment PIN_AK4 -to ADC_SDI
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to ADC_SDI
set_location_assignment PIN_AK3 -to ADC_SDO
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to ADC_SDO

# Machine outputs (OUTPUT frames; docs/architecture.md "Pins"): GPIO_0[10..16] (pins
# from the Terasic DE1-SoC manual), high = on, to driver stages (relay / MOSFET) for the coolant
# valves, the part-cooling fan (PWM) and the digital outputs.
set_location_assignment PIN_AH18 -to coolant_flood
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to coolant_flood
set_location_assignment PIN_AH17 -to coolant_mist
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to coolant_mist
set_location_assignment PIN_AG16 -to fan
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to fan
set_location_assignment PIN_AE16 -to dout[0]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to dout[0]
set_location_assignment PIN_AF16 -to dout[1]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to dout[1]
set_location_assignment PIN_AG17 -to dout[2]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to dout[2]
set_location_assignment PIN_AA18 -to dout[3]
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to dout[3]

# Limit switches (docs/machine.md): GPIO_0[17..20] (pins from the Terasic DE1-SoC manual),
# normally-closed switches to ground with the weak pull-up on, so that a pressed switch or an open
# wire reads high (asserted). Which are wired: de1soc_top's LIMIT_ENABLE.
set_location_assignment PIN_AA19 -to lim_x_min
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to lim_x_min
set_instance_assignment -name WEAK_PULL_UP_RESISTOR ON -to lim_x_min
set_location_assignment PIN_AE17 -to lim_x_max
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to lim_x_max
set_instance_assignment -name WEAK_PULL_UP_RESISTOR ON -to lim_x_max
set_location_assignment PIN_AC20 -to lim_y_min
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to lim_y_min
set_instance_assignment -name WEAK_PULL_UP_RESISTOR ON -to lim_y_min
set_location_assignment PIN_AH19 -to lim_y_max
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to lim_y_max
set_instance_assignment -name WEAK_PULL_UP_RESISTOR ON -to lim_y_max

# Probe (docs/machine.md "Homing and probing (hardware)"): GPIO_0[21] (pin from the Terasic
# DE1-SoC manual), weak pull-up on, active low: a touch plate or a normally-open probe switch to
# ground reads low at contact.
set_location_assignment PIN_AJ20 -to probe_n
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to probe_n
set_instance_assignment -name WEAK_PULL_UP_RESISTOR ON -to probe_n

# Laser power / spindle speed PWM (docs/machine.md "Laser and spindle PWM"): GPIO_0[22] (pin from
# the Terasic DE1-SoC manual), high = on, to the laser driver's PWM / TTL input or a spindle
# controller's PWM input.
set_location_assignment PIN_AH20 -to spindle_pwm
set_instance_assignment -name IO_STANDARD "3.3-V LVTTL" -to spindle_pwm
