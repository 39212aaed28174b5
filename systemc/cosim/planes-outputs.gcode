(Arcs in the three planes as ARC frames, and outputs between the moves: sim_both_planes_outputs)
G21 G90 F9000
G0 X1 Y1 Z0
M8
M106 S128
G18 G2 X2 Z0 I0.5 K0
M62 P2
G19 G3 Y2 Z0 J0.5 K0
M9
M107
M63 P2
G17 G2 X1 Y2 I-0.5 J0
M2
