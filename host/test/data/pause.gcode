; A pause and a message between two moves (stream_pause_* tests)
G21 G90 F1200
G1 X5
M117 before the stop
M0
G1 X10
M2
