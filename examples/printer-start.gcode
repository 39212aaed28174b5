; Printer start sequence (heaters, issue 7): bed and hot end heat together, then the job waits for
; both (M190/M109: within heater.*.wait_tolerance_c for wait_settle_s). Put in front of a print
; that has no heater commands, e.g. the corpus part.gcode (make soak does).
M140 S60 ; bed target, no wait
M104 S200 ; hot end target, no wait
M190 S60 ; wait for the bed
M109 S200 ; wait for the hot end
