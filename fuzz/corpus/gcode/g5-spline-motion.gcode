G1 Z1.0 F3000
G02
 E9G90
G21
GZ0.25 F900.0 E2.40448
G1 X117.1433 Y77.4764 Z0.25 F91949
G1 X77.4809 Y117.1449 Z0.25 F900.0 E3.51511
G1 E2.51511 F1800.0
; G21         ; Set units to mm
G90         ; Absolute positioning

;
; Operation:    0
; Name:         
; Type:         Enÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿg3000
G02
 E9G90
G21
GZ0rave
; Paths:        5
; Direction: inkscapentioÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿnal
; Cut Depth:    0.9999999999999999
; ÿÿÿÿÿÿÿÿÿÿÿnal
; Cut Depth:    0.999997
; Cut r_selG1 X117.1433 Y77.4764 Z0.25 F91949
G1 X77.4809 Y117.1449 Z0.25 F900.0 E3.51511
G1 E2.51511 F1800.0
; G21         ; Set units to mm
G90         ; Absolute positioning

;
; Operation:    0
; Name:         
; Type:         Enÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿgrave
; Paths:        5
; Direction: inkscapentioÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿÿnal
; Cut Depth:    0.9999999999999999
; Pass Depth:   3.175
; Plunge rate:  127
; Cut r_sele    1016
;

; Path 0
; Rapid to initiae    1016
;

; Path 0
; Rapid to initial position
G1 X43.9090 Y-28.2880 F1500
S0.7545
; S1.0
G5 X84.97M3 S80
G4 P0.5
; cut
G1 X43.7449 Y-28.2892 F100
G1 X43.6631 Y-28.2908
G1 X43.5816 Y-28.2928
G1 X43.5000 Y-28.2956
G1 X43.4188 Y-28.2989
G1 X43.3321 Y-29.8077
