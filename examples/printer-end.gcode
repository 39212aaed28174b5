; Printer end sequence: heaters off.
M104 S0
M140 S0
