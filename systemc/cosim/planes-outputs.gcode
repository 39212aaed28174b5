(Arcs in the three planes as ARC frames, and outputs between the moves: sim_both_planes_outputs)
G21 G90 F6000
G0 X10 Y5 Z0
M8
M106 S128
G18 G2 X12 Z0 I1 K0
M62 P2
G19 G3 Y7 Z0 J1 K0
M9
M107
M63 P2
G17 G2 X10 Y7 I-1 J0
M2
