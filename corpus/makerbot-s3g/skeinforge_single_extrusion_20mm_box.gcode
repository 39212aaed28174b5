(<version> 12.01.13 </version>)
(<created> 12.06.01|17:47 </created>)
(<extruderInitialization>)
(<craftTypeName> extrusion </craftTypeName>)
M105
(<decimalPlacesCarried> 3 </decimalPlacesCarried>)
(<infillPerimeterOverlap> 0.3 </infillPerimeterOverlap>)
(<infillWidth> 0.4 </infillWidth>)
(<layerThickness> 0.27 </layerThickness>)
(<threadSequenceString> loops perimeter infill </threadSequenceString>)
(<maximumZFeedRatePerSecond> 999.0 </maximumZFeedRatePerSecond>)
(<objectFirstLayerFeedRateInfillMultiplier> 0.9 </objectFirstLayerFeedRateInfillMultiplier>)
(<operatingFeedRatePerSecond> 30.0 </operatingFeedRatePerSecond>)
(<objectFirstLayerFlowRateInfillMultiplier> 0.8 </objectFirstLayerFlowRateInfillMultiplier>)
(<operatingFlowRate> 30.0 </operatingFlowRate>)
(<orbitalFeedRatePerSecond> 0.0 </orbitalFeedRatePerSecond>)
(<travelFeedRatePerSecond> 50.0 </travelFeedRatePerSecond>)
(<perimeterWidth> 0.4 </perimeterWidth>)
(<profileName> ABS </profileName>)
(<settings>)
(<setting> alteration Activate_Alteration True </setting>)
(<setting> alteration Name_of_End_File:  </setting>)
(<setting> alteration Name_of_Start_File:  </setting>)
(<setting> alteration Remove_Redundant_Mcode True </setting>)
(<setting> alteration Replace_Variable_with_Setting True </setting>)
(<setting> comb Activate_Comb True </setting>)
(<setting> comb Running_Jump_Space_(mm): 2.0 </setting>)
(<setting> cool Activate_Cool True </setting>)
(<setting> cool Bridge_Cool_(Celcius): 1.0 </setting>)
(<setting> cool Orbit False </setting>)
(<setting> cool Slow_Down True </setting>)
(<setting> cool Maximum_Cool_(Celcius): 1.0 </setting>)
(<setting> cool Minimum_Layer_Time_(seconds): 5.0 </setting>)
(<setting> cool Minimum_Orbital_Radius_(millimeters): 10.0 </setting>)
(<setting> cool Name_of_Cool_End_File: cool_end.gcode </setting>)
(<setting> cool Name_of_Cool_Start_File: cool_start.gcode </setting>)
(<setting> cool Orbital_Outset_(millimeters): 2.0 </setting>)
(<setting> cool Turn_Fan_On_at_Beginning False </setting>)
(<setting> cool Turn_Fan_Off_at_Ending False </setting>)
(<setting> dimension Activate_Dimension True </setting>)
(<setting> dimension Absolute_Extrusion_Distance True </setting>)
(<setting> dimension Relative_Extrusion_Distance False </setting>)
(<setting> dimension Extruder_Retraction_Speed_(mm/s): 13.3 </setting>)
(<setting> dimension Filament_Diameter_(mm): 1.82 </setting>)
(<setting> dimension Filament_Packing_Density_(ratio): 0.85 </setting>)
(<setting> dimension Maximum_E_Value_before_Reset_(float): 91234.0 </setting>)
(<setting> dimension Minimum_Travel_for_Retraction_(millimeters): 1.0 </setting>)
(<setting> dimension Retract_Within_Island False </setting>)
(<setting> dimension Retraction_Distance_(millimeters): 0.5 </setting>)
(<setting> dimension Restart_Extra_Distance_(millimeters): -0.2 </setting>)
(<setting> export Activate_Export True </setting>)
(<setting> export Add_Descriptive_Extension False </setting>)
(<setting> export Add_Export_Suffix False </setting>)
(<setting> export Add_Profile_Extension False </setting>)
(<setting> export Add_Timestamp_Extension False </setting>)
(<setting> export Also_Send_Output_To:  </setting>)
(<setting> export Analyze_Gcode True </setting>)
(<setting> export Do_Not_Delete_Comments True </setting>)
(<setting> export Delete_Crafting_Comments False </setting>)
(<setting> export Delete_All_Comments False </setting>)
(<setting> export Do_Not_Change_Output True </setting>)
(<setting> export binary_16_byte False </setting>)
(<setting> export gcode_step False </setting>)
(<setting> export gcode_time_segment False </setting>)
(<setting> export gcode_small False </setting>)
(<setting> export File_Extension: gcode </setting>)
(<setting> export Name_of_Replace_File: replace.csv </setting>)
(<setting> export Save_Penultimate_Gcode False </setting>)
(<setting> fill Activate_Fill True </setting>)
(<setting> fill Diaphragm_Period_(layers): 100 </setting>)
(<setting> fill Diaphragm_Thickness_(layers): 0 </setting>)
(<setting> fill Extra_Shells_on_Alternating_Solid_Layer_(layers): 1 </setting>)
(<setting> fill Extra_Shells_on_Base_(layers): 1 </setting>)
(<setting> fill Extra_Shells_on_Sparse_Layer_(layers): 1 </setting>)
(<setting> fill Grid_Circle_Separation_over_Perimeter_Width_(ratio): 0.2 </setting>)
(<setting> fill Grid_Extra_Overlap_(ratio): 0.1 </setting>)
(<setting> fill Grid_Junction_Separation_Band_Height_(layers): 10 </setting>)
(<setting> fill Grid_Junction_Separation_over_Octogon_Radius_At_End_(ratio): 0.0 </setting>)
(<setting> fill Grid_Junction_Separation_over_Octogon_Radius_At_Middle_(ratio): 0.0 </setting>)
(<setting> fill Infill_Begin_Rotation_(degrees): 90.0 </setting>)
(<setting> fill Infill_Begin_Rotation_Repeat_(layers): 1 </setting>)
(<setting> fill Infill_Odd_Layer_Extra_Rotation_(degrees): 90.0 </setting>)
(<setting> fill Grid_Circular False </setting>)
(<setting> fill Grid_Hexagonal True </setting>)
(<setting> fill Grid_Rectangular False </setting>)
(<setting> fill Line False </setting>)
(<setting> fill Infill_Perimeter_Overlap_(ratio): 0.3 </setting>)
(<setting> fill Infill_Solidity_(ratio): 0.1 </setting>)
(<setting> fill Infill_Width_over_Thickness_(ratio): 1.48148148148 </setting>)
(<setting> fill Solid_Surface_Thickness_(layers): 3 </setting>)
(<setting> fill Lower_Left True </setting>)
(<setting> fill Nearest False </setting>)
(<setting> fill Surrounding_Angle_(degrees): 60.0 </setting>)
(<setting> fill Infill_>_Loops_>_Perimeter False </setting>)
(<setting> fill Infill_>_Perimeter_>_Loops False </setting>)
(<setting> fill Loops_>_Infill_>_Perimeter False </setting>)
(<setting> fill Loops_>_Perimeter_>_Infill True </setting>)
(<setting> fill Perimeter_>_Infill_>_Loops False </setting>)
(<setting> fill Perimeter_>_Loops_>_Infill False </setting>)
(<setting> home Activate_Home True </setting>)
(<setting> home Name_of_Home_File: home.gcode </setting>)
(<setting> jitter Activate_Jitter True </setting>)
(<setting> jitter Jitter_Over_Perimeter_Width_(ratio): 2.0 </setting>)
(<setting> raft Activate_Raft True </setting>)
(<setting> raft Add_Raft,_Elevate_Nozzle,_Orbit: False </setting>)
(<setting> raft Base_Feed_Rate_Multiplier_(ratio): 0.75 </setting>)
(<setting> raft Base_Flow_Rate_Multiplier_(ratio): 0.6 </setting>)
(<setting> raft Base_Infill_Density_(ratio): 0.3 </setting>)
(<setting> raft Base_Layer_Thickness_over_Layer_Thickness: 2.2 </setting>)
(<setting> raft Base_Layers_(integer): 1 </setting>)
(<setting> raft Base_Nozzle_Lift_over_Base_Layer_Thickness_(ratio): 0.3 </setting>)
(<setting> raft Initial_Circling: False </setting>)
(<setting> raft Infill_Overhang_over_Extrusion_Width_(ratio): 0.1 </setting>)
(<setting> raft Interface_Feed_Rate_Multiplier_(ratio): 1.5 </setting>)
(<setting> raft Interface_Flow_Rate_Multiplier_(ratio): 0.7 </setting>)
(<setting> raft Interface_Infill_Density_(ratio): 0.4 </setting>)
(<setting> raft Interface_Layer_Thickness_over_Layer_Thickness: 1.8 </setting>)
(<setting> raft Interface_Layers_(integer): 2 </setting>)
(<setting> raft Interface_Nozzle_Lift_over_Interface_Layer_Thickness_(ratio): 0.3 </setting>)
(<setting> raft Name_of_Support_End_File: support_end.gcode </setting>)
(<setting> raft Name_of_Support_Start_File: support_start.gcode </setting>)
(<setting> raft Operating_Nozzle_Lift_over_Layer_Thickness_(ratio): 0.0 </setting>)
(<setting> raft Raft_Additional_Margin_over_Length_(%): 2.5 </setting>)
(<setting> raft Raft_Margin_(mm): 2.5 </setting>)
(<setting> raft Support_Cross_Hatch False </setting>)
(<setting> raft Support_Flow_Rate_over_Operating_Flow_Rate_(ratio): 0.7 </setting>)
(<setting> raft Support_Gap_over_Perimeter_Extrusion_Width_(ratio): 0.005 </setting>)
(<setting> raft None True </setting>)
(<setting> raft Empty_Layers_Only False </setting>)
(<setting> raft Everywhere False </setting>)
(<setting> raft Exterior_Only False </setting>)
(<setting> raft Support_Minimum_Angle_(degrees): 45.0 </setting>)
(<setting> speed Activate_Speed True </setting>)
(<setting> speed Add_Flow_Rate: True </setting>)
(<setting> speed Bridge_Feed_Rate_Multiplier_(ratio): 1.0 </setting>)
(<setting> speed Bridge_Flow_Rate_Multiplier_(ratio): 1.0 </setting>)
(<setting> speed Duty_Cyle_at_Beginning_(portion): 1.0 </setting>)
(<setting> speed Duty_Cyle_at_Ending_(portion): 0.0 </setting>)
(<setting> speed Feed_Rate_(mm/s): 30.0 </setting>)
(<setting> speed Flow_Rate_Setting_(float): 30.0 </setting>)
(<setting> speed Object_First_Layer_Feed_Rate_Infill_Multiplier_(ratio): 0.9 </setting>)
(<setting> speed Object_First_Layer_Feed_Rate_Perimeter_Multiplier_(ratio): 0.9 </setting>)
(<setting> speed Object_First_Layer_Flow_Rate_Infill_Multiplier_(ratio): 0.8 </setting>)
(<setting> speed Object_First_Layer_Flow_Rate_Perimeter_Multiplier_(ratio): 0.9 </setting>)
(<setting> speed Orbital_Feed_Rate_over_Operating_Feed_Rate_(ratio): 0.0 </setting>)
(<setting> speed Maximum_Z_Feed_Rate_(mm/s): 999.0 </setting>)
(<setting> speed Perimeter_Feed_Rate_Multiplier_(ratio): 0.5 </setting>)
(<setting> speed Perimeter_Flow_Rate_Multiplier_(ratio): 0.5 </setting>)
(<setting> speed Travel_Feed_Rate_(mm/s): 50.0 </setting>)
(</settings>)
(<timeStampPreface> 20120601_174712 </timeStampPreface>)
(<procedureName> carve </procedureName>)
(<procedureName> preface </procedureName>)
(<procedureName> inset </procedureName>)
(<procedureName> fill </procedureName>)
(<procedureName> speed </procedureName>)
(<procedureName> raft </procedureName>)
(<procedureName> jitter </procedureName>)
(<procedureName> comb </procedureName>)
(<procedureName> cool </procedureName>)
(<procedureName> dimension </procedureName>)
(<procedureName> alteration </procedureName>)
(<procedureName> export </procedureName>)
(</extruderInitialization>)
(<crafting>)
;M113 S1.0
;M108 R13.5
M73 P4 (display progress)
(<layer> 0.135 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z0.135 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z0.135 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z0.135 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z0.135 </boundaryPoint>)
(<perimeter> outer )
G1 X-9.8 Y-9.79 Z0.14 F3000.0
G1 F798.0
G1 E0.3
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z0.14 F810.0 E0.3
G1 X9.8 Y-9.8 Z0.14 F810.0 E1.258
G1 X9.8 Y9.8 Z0.14 F810.0 E2.215
G1 X-9.8 Y9.8 Z0.14 F810.0 E3.172
G1 X-9.8 Y-9.79 Z0.14 F810.0 E4.129
G1 F798.0
G1 E4.129
G1 F810.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<loop> outer )
;M108 R24.0
G1 X-9.4 Y-9.39 Z0.14 F3000.0
G1 F798.0
G1 E4.129
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z0.14 F1620.0 E4.129
G1 X9.4 Y-9.4 Z0.14 F1620.0 E4.945
G1 X9.4 Y9.4 Z0.14 F1620.0 E5.762
G1 X-9.4 Y9.4 Z0.14 F1620.0 E6.578
G1 X-9.4 Y-9.39 Z0.14 F1620.0 E7.394
G1 F798.0
G1 E6.894
G1 F1620.0
M103
(</loop>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z0.135 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z0.135 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z0.135 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z0.135 </infillPoint>)
(</infillBoundary>)
G1 X-0.0 Y-9.12 Z0.14 F3000.0
G1 F798.0
G1 E7.194
G1 F3000.0
M101
G1 X0.0 Y9.12 Z0.14 F1620.0 E7.986
G1 X-0.4 Y9.12 Z0.14 F1620.0 E8.003
G1 X-0.4 Y-9.12 Z0.14 F1620.0 E8.795
G1 X-0.8 Y-9.12 Z0.14 F1620.0 E8.812
G1 X-0.8 Y9.12 Z0.14 F1620.0 E9.604
G1 X-1.2 Y9.12 Z0.14 F1620.0 E9.621
G1 X-1.2 Y-9.12 Z0.14 F1620.0 E10.413
G1 X-1.6 Y-9.12 Z0.14 F1620.0 E10.431
G1 X-1.6 Y9.12 Z0.14 F1620.0 E11.222
G1 X-2.0 Y9.12 Z0.14 F1620.0 E11.24
G1 X-2.0 Y-9.12 Z0.14 F1620.0 E12.032
G1 X-2.4 Y-9.12 Z0.14 F1620.0 E12.049
G1 X-2.4 Y9.12 Z0.14 F1620.0 E12.841
G1 X-2.8 Y9.12 Z0.14 F1620.0 E12.858
G1 X-2.8 Y-9.12 Z0.14 F1620.0 E13.65
G1 X-3.2 Y-9.12 Z0.14 F1620.0 E13.667
G1 X-3.2 Y9.12 Z0.14 F1620.0 E14.459
G1 X-3.6 Y9.12 Z0.14 F1620.0 E14.477
G1 X-3.6 Y-9.12 Z0.14 F1620.0 E15.268
G1 X-4.0 Y-9.12 Z0.14 F1620.0 E15.286
G1 X-4.0 Y9.12 Z0.14 F1620.0 E16.078
G1 X-4.4 Y9.12 Z0.14 F1620.0 E16.095
G1 X-4.4 Y-9.12 Z0.14 F1620.0 E16.887
G1 X-4.8 Y-9.12 Z0.14 F1620.0 E16.904
G1 X-4.8 Y9.12 Z0.14 F1620.0 E17.696
G1 X-5.2 Y9.12 Z0.14 F1620.0 E17.714
G1 X-5.2 Y-9.12 Z0.14 F1620.0 E18.505
G1 X-5.6 Y-9.12 Z0.14 F1620.0 E18.523
G1 X-5.6 Y9.12 Z0.14 F1620.0 E19.315
G1 X-6.0 Y9.12 Z0.14 F1620.0 E19.332
G1 X-6.0 Y-9.12 Z0.14 F1620.0 E20.124
G1 X-6.4 Y-9.12 Z0.14 F1620.0 E20.141
G1 X-6.4 Y9.12 Z0.14 F1620.0 E20.933
G1 X-6.8 Y9.12 Z0.14 F1620.0 E20.95
G1 X-6.8 Y-9.12 Z0.14 F1620.0 E21.742
G1 X-7.2 Y-9.12 Z0.14 F1620.0 E21.76
G1 X-7.2 Y9.12 Z0.14 F1620.0 E22.551
G1 X-7.6 Y9.12 Z0.14 F1620.0 E22.569
G1 X-7.6 Y-9.12 Z0.14 F1620.0 E23.361
G1 X-8.0 Y-9.12 Z0.14 F1620.0 E23.378
G1 X-8.0 Y9.12 Z0.14 F1620.0 E24.17
G1 X-8.4 Y9.12 Z0.14 F1620.0 E24.187
G1 X-8.4 Y-9.12 Z0.14 F1620.0 E24.979
G1 X-8.8 Y-9.12 Z0.14 F1620.0 E24.996
G1 X-8.8 Y9.12 Z0.14 F1620.0 E25.788
G1 F798.0
G1 E25.288
G1 F1620.0
M103
G1 X0.4 Y9.12 Z0.14 F3000.0
G1 F798.0
G1 E25.588
G1 F3000.0
M101
G1 X0.4 Y-9.12 Z0.14 F1620.0 E26.38
G1 X0.8 Y-9.12 Z0.14 F1620.0 E26.398
G1 X0.8 Y9.12 Z0.14 F1620.0 E27.189
G1 X1.2 Y9.12 Z0.14 F1620.0 E27.207
G1 X1.2 Y-9.12 Z0.14 F1620.0 E27.999
G1 X1.6 Y-9.12 Z0.14 F1620.0 E28.016
G1 X1.6 Y9.12 Z0.14 F1620.0 E28.808
G1 X2.0 Y9.12 Z0.14 F1620.0 E28.825
G1 X2.0 Y-9.12 Z0.14 F1620.0 E29.617
G1 X2.4 Y-9.12 Z0.14 F1620.0 E29.634
G1 X2.4 Y9.12 Z0.14 F1620.0 E30.426
G1 X2.8 Y9.12 Z0.14 F1620.0 E30.444
G1 X2.8 Y-9.12 Z0.14 F1620.0 E31.235
G1 X3.2 Y-9.12 Z0.14 F1620.0 E31.253
G1 X3.2 Y9.12 Z0.14 F1620.0 E32.045
G1 X3.6 Y9.12 Z0.14 F1620.0 E32.062
G1 X3.6 Y-9.12 Z0.14 F1620.0 E32.854
G1 X4.0 Y-9.12 Z0.14 F1620.0 E32.871
G1 X4.0 Y9.12 Z0.14 F1620.0 E33.663
G1 X4.4 Y9.12 Z0.14 F1620.0 E33.681
G1 X4.4 Y-9.12 Z0.14 F1620.0 E34.472
G1 X4.8 Y-9.12 Z0.14 F1620.0 E34.49
G1 X4.8 Y9.12 Z0.14 F1620.0 E35.282
G1 X5.2 Y9.12 Z0.14 F1620.0 E35.299
G1 X5.2 Y-9.12 Z0.14 F1620.0 E36.091
G1 X5.6 Y-9.12 Z0.14 F1620.0 E36.108
G1 X5.6 Y9.12 Z0.14 F1620.0 E36.9
G1 X6.0 Y9.12 Z0.14 F1620.0 E36.917
G1 X6.0 Y-9.12 Z0.14 F1620.0 E37.709
G1 X6.4 Y-9.12 Z0.14 F1620.0 E37.727
G1 X6.4 Y9.12 Z0.14 F1620.0 E38.518
G1 X6.8 Y9.12 Z0.14 F1620.0 E38.536
G1 X6.8 Y-9.12 Z0.14 F1620.0 E39.328
G1 X7.2 Y-9.12 Z0.14 F1620.0 E39.345
G1 X7.2 Y9.12 Z0.14 F1620.0 E40.137
G1 X7.6 Y9.12 Z0.14 F1620.0 E40.154
G1 X7.6 Y-9.12 Z0.14 F1620.0 E40.946
G1 X8.0 Y-9.12 Z0.14 F1620.0 E40.963
G1 X8.0 Y9.12 Z0.14 F1620.0 E41.755
G1 X8.4 Y9.12 Z0.14 F1620.0 E41.773
G1 X8.4 Y-9.12 Z0.14 F1620.0 E42.565
G1 X8.8 Y-9.12 Z0.14 F1620.0 E42.582
G1 X8.8 Y9.12 Z0.14 F1620.0 E43.374
G1 F798.0
G1 E42.874
G1 F1620.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
;M108 R30.0
M73 P7 (display progress)
(<layer> 0.405 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z0.405 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z0.405 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z0.405 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z0.405 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.09 Z0.41 F3000.0
G1 F798.0
G1 E43.174
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z0.41 F1800.0 E43.189
G1 X9.4 Y-9.4 Z0.41 F1800.0 E44.107
G1 X9.4 Y9.4 Z0.41 F1800.0 E45.025
G1 X-9.4 Y9.4 Z0.41 F1800.0 E45.944
G1 X-9.4 Y-9.09 Z0.41 F1800.0 E46.847
G1 F798.0
G1 E46.847
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.09 Z0.41 F3000.0
G1 F798.0
G1 E46.847
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z0.41 F900.0 E46.862
G1 X-9.8 Y-9.8 Z0.41 F900.0 E46.881
G1 X9.8 Y-9.8 Z0.41 F900.0 E47.838
G1 X9.8 Y9.8 Z0.41 F900.0 E48.796
G1 X-9.8 Y9.8 Z0.41 F900.0 E49.753
G1 X-9.8 Y-9.09 Z0.41 F900.0 E50.676
G1 F798.0
G1 E50.176
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z0.405 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z0.405 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z0.405 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z0.405 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X9.12 Y-0.0 Z0.41 F3000.0
G1 F798.0
G1 E50.476
G1 F3000.0
M101
G1 X-9.12 Y0.0 Z0.41 F1800.0 E51.366
G1 X-9.12 Y-0.4 Z0.41 F1800.0 E51.386
G1 X9.12 Y-0.4 Z0.41 F1800.0 E52.277
G1 X9.12 Y-0.8 Z0.41 F1800.0 E52.296
G1 X-9.12 Y-0.8 Z0.41 F1800.0 E53.187
G1 X-9.12 Y-1.2 Z0.41 F1800.0 E53.207
G1 X9.12 Y-1.2 Z0.41 F1800.0 E54.097
G1 X9.12 Y-1.6 Z0.41 F1800.0 E54.117
G1 X-9.12 Y-1.6 Z0.41 F1800.0 E55.008
G1 X-9.12 Y-2.0 Z0.41 F1800.0 E55.027
G1 X9.12 Y-2.0 Z0.41 F1800.0 E55.918
G1 X9.12 Y-2.4 Z0.41 F1800.0 E55.938
G1 X-9.12 Y-2.4 Z0.41 F1800.0 E56.829
G1 X-9.12 Y-2.8 Z0.41 F1800.0 E56.848
G1 X9.12 Y-2.8 Z0.41 F1800.0 E57.739
G1 X9.12 Y-3.2 Z0.41 F1800.0 E57.758
G1 X-9.12 Y-3.2 Z0.41 F1800.0 E58.649
G1 X-9.12 Y-3.6 Z0.41 F1800.0 E58.669
G1 X9.12 Y-3.6 Z0.41 F1800.0 E59.56
G1 X9.12 Y-4.0 Z0.41 F1800.0 E59.579
G1 X-9.12 Y-4.0 Z0.41 F1800.0 E60.47
G1 X-9.12 Y-4.4 Z0.41 F1800.0 E60.49
G1 X9.12 Y-4.4 Z0.41 F1800.0 E61.38
G1 X9.12 Y-4.8 Z0.41 F1800.0 E61.4
G1 X-9.12 Y-4.8 Z0.41 F1800.0 E62.291
G1 X-9.12 Y-5.2 Z0.41 F1800.0 E62.31
G1 X9.12 Y-5.2 Z0.41 F1800.0 E63.201
G1 X9.12 Y-5.6 Z0.41 F1800.0 E63.221
G1 X-9.12 Y-5.6 Z0.41 F1800.0 E64.112
G1 X-9.12 Y-6.0 Z0.41 F1800.0 E64.131
G1 X9.12 Y-6.0 Z0.41 F1800.0 E65.022
G1 X9.12 Y-6.4 Z0.41 F1800.0 E65.041
G1 X-9.12 Y-6.4 Z0.41 F1800.0 E65.932
G1 X-9.12 Y-6.8 Z0.41 F1800.0 E65.952
G1 X9.12 Y-6.8 Z0.41 F1800.0 E66.843
G1 X9.12 Y-7.2 Z0.41 F1800.0 E66.862
G1 X-9.12 Y-7.2 Z0.41 F1800.0 E67.753
G1 X-9.12 Y-7.6 Z0.41 F1800.0 E67.773
G1 X9.12 Y-7.6 Z0.41 F1800.0 E68.663
G1 X9.12 Y-8.0 Z0.41 F1800.0 E68.683
G1 X-9.12 Y-8.0 Z0.41 F1800.0 E69.574
G1 X-9.12 Y-8.4 Z0.41 F1800.0 E69.593
G1 X9.12 Y-8.4 Z0.41 F1800.0 E70.484
G1 X9.12 Y-8.8 Z0.41 F1800.0 E70.504
G1 X-9.12 Y-8.8 Z0.41 F1800.0 E71.395
G1 F798.0
G1 E70.895
G1 F1800.0
M103
G1 X-9.12 Y0.4 Z0.41 F3000.0
G1 F798.0
G1 E71.195
G1 F3000.0
M101
G1 X9.12 Y0.4 Z0.41 F1800.0 E72.085
G1 X9.12 Y0.8 Z0.41 F1800.0 E72.105
G1 X-9.12 Y0.8 Z0.41 F1800.0 E72.996
G1 X-9.12 Y1.2 Z0.41 F1800.0 E73.015
G1 X9.12 Y1.2 Z0.41 F1800.0 E73.906
G1 X9.12 Y1.6 Z0.41 F1800.0 E73.926
G1 X-9.12 Y1.6 Z0.41 F1800.0 E74.816
G1 X-9.12 Y2.0 Z0.41 F1800.0 E74.836
G1 X9.12 Y2.0 Z0.41 F1800.0 E75.727
G1 X9.12 Y2.4 Z0.41 F1800.0 E75.746
G1 X-9.12 Y2.4 Z0.41 F1800.0 E76.637
G1 X-9.12 Y2.8 Z0.41 F1800.0 E76.657
G1 X9.12 Y2.8 Z0.41 F1800.0 E77.548
G1 X9.12 Y3.2 Z0.41 F1800.0 E77.567
G1 X-9.12 Y3.2 Z0.41 F1800.0 E78.458
G1 X-9.12 Y3.6 Z0.41 F1800.0 E78.477
G1 X9.12 Y3.6 Z0.41 F1800.0 E79.368
G1 X9.12 Y4.0 Z0.41 F1800.0 E79.388
G1 X-9.12 Y4.0 Z0.41 F1800.0 E80.279
G1 X-9.12 Y4.4 Z0.41 F1800.0 E80.298
G1 X9.12 Y4.4 Z0.41 F1800.0 E81.189
G1 X9.12 Y4.8 Z0.41 F1800.0 E81.209
G1 X-9.12 Y4.8 Z0.41 F1800.0 E82.099
G1 X-9.12 Y5.2 Z0.41 F1800.0 E82.119
G1 X9.12 Y5.2 Z0.41 F1800.0 E83.01
G1 X9.12 Y5.6 Z0.41 F1800.0 E83.029
G1 X-9.12 Y5.6 Z0.41 F1800.0 E83.92
G1 X-9.12 Y6.0 Z0.41 F1800.0 E83.94
G1 X9.12 Y6.0 Z0.41 F1800.0 E84.831
G1 X9.12 Y6.4 Z0.41 F1800.0 E84.85
G1 X-9.12 Y6.4 Z0.41 F1800.0 E85.741
G1 X-9.12 Y6.8 Z0.41 F1800.0 E85.76
G1 X9.12 Y6.8 Z0.41 F1800.0 E86.651
G1 X9.12 Y7.2 Z0.41 F1800.0 E86.671
G1 X-9.12 Y7.2 Z0.41 F1800.0 E87.562
G1 X-9.12 Y7.6 Z0.41 F1800.0 E87.581
G1 X9.12 Y7.6 Z0.41 F1800.0 E88.472
G1 X9.12 Y8.0 Z0.41 F1800.0 E88.492
G1 X-9.12 Y8.0 Z0.41 F1800.0 E89.382
G1 X-9.12 Y8.4 Z0.41 F1800.0 E89.402
G1 X9.12 Y8.4 Z0.41 F1800.0 E90.293
G1 X9.12 Y8.8 Z0.41 F1800.0 E90.312
G1 X-9.12 Y8.8 Z0.41 F1800.0 E91.203
G1 F798.0
G1 E90.703
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
(<operatingLayerEnd> </operatingLayerEnd>)
M73 P10 (display progress)
(<layer> 0.675 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z0.675 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z0.675 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z0.675 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z0.675 </boundaryPoint>)
(<loop> outer )
G1 X-9.22 Y-9.4 Z0.68 F3000.0
G1 F798.0
G1 E91.003
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z0.68 F1800.0 E91.912
G1 X9.4 Y9.4 Z0.68 F1800.0 E92.831
G1 X-9.4 Y9.4 Z0.68 F1800.0 E93.749
G1 X-9.4 Y-9.4 Z0.68 F1800.0 E94.667
G1 X-9.22 Y-9.4 Z0.68 F1800.0 E94.676
G1 F798.0
G1 E94.676
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.58 Z0.68 F3000.0
G1 F798.0
G1 E94.676
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z0.68 F900.0 E94.686
G1 X9.8 Y-9.8 Z0.68 F900.0 E95.644
G1 X9.8 Y9.8 Z0.68 F900.0 E96.601
G1 X-9.8 Y9.8 Z0.68 F900.0 E97.558
G1 X-9.8 Y-9.4 Z0.68 F900.0 E98.496
G1 X-9.8 Y-9.58 Z0.68 F900.0 E98.505
G1 F798.0
G1 E98.005
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z0.675 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z0.675 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z0.675 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z0.675 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-0.0 Y-9.12 Z0.68 F3000.0
G1 F798.0
G1 E98.305
G1 F3000.0
M101
G1 X0.0 Y9.12 Z0.68 F1800.0 E99.196
G1 X-0.4 Y9.12 Z0.68 F1800.0 E99.215
G1 X-0.4 Y-9.12 Z0.68 F1800.0 E100.106
G1 X-0.8 Y-9.12 Z0.68 F1800.0 E100.126
G1 X-0.8 Y9.12 Z0.68 F1800.0 E101.016
G1 X-1.2 Y9.12 Z0.68 F1800.0 E101.036
G1 X-1.2 Y-9.12 Z0.68 F1800.0 E101.927
G1 X-1.6 Y-9.12 Z0.68 F1800.0 E101.946
G1 X-1.6 Y9.12 Z0.68 F1800.0 E102.837
G1 X-2.0 Y9.12 Z0.68 F1800.0 E102.857
G1 X-2.0 Y-9.12 Z0.68 F1800.0 E103.748
G1 X-2.4 Y-9.12 Z0.68 F1800.0 E103.767
G1 X-2.4 Y9.12 Z0.68 F1800.0 E104.658
G1 X-2.8 Y9.12 Z0.68 F1800.0 E104.677
G1 X-2.8 Y-9.12 Z0.68 F1800.0 E105.568
G1 X-3.2 Y-9.12 Z0.68 F1800.0 E105.588
G1 X-3.2 Y9.12 Z0.68 F1800.0 E106.479
G1 X-3.6 Y9.12 Z0.68 F1800.0 E106.498
G1 X-3.6 Y-9.12 Z0.68 F1800.0 E107.389
G1 X-4.0 Y-9.12 Z0.68 F1800.0 E107.409
G1 X-4.0 Y9.12 Z0.68 F1800.0 E108.299
G1 X-4.4 Y9.12 Z0.68 F1800.0 E108.319
G1 X-4.4 Y-9.12 Z0.68 F1800.0 E109.21
G1 X-4.8 Y-9.12 Z0.68 F1800.0 E109.229
G1 X-4.8 Y9.12 Z0.68 F1800.0 E110.12
G1 X-5.2 Y9.12 Z0.68 F1800.0 E110.14
G1 X-5.2 Y-9.12 Z0.68 F1800.0 E111.031
G1 X-5.6 Y-9.12 Z0.68 F1800.0 E111.05
G1 X-5.6 Y9.12 Z0.68 F1800.0 E111.941
G1 X-6.0 Y9.12 Z0.68 F1800.0 E111.96
G1 X-6.0 Y-9.12 Z0.68 F1800.0 E112.851
G1 X-6.4 Y-9.12 Z0.68 F1800.0 E112.871
G1 X-6.4 Y9.12 Z0.68 F1800.0 E113.762
G1 X-6.8 Y9.12 Z0.68 F1800.0 E113.781
G1 X-6.8 Y-9.12 Z0.68 F1800.0 E114.672
G1 X-7.2 Y-9.12 Z0.68 F1800.0 E114.692
G1 X-7.2 Y9.12 Z0.68 F1800.0 E115.582
G1 X-7.6 Y9.12 Z0.68 F1800.0 E115.602
G1 X-7.6 Y-9.12 Z0.68 F1800.0 E116.493
G1 X-8.0 Y-9.12 Z0.68 F1800.0 E116.512
G1 X-8.0 Y9.12 Z0.68 F1800.0 E117.403
G1 X-8.4 Y9.12 Z0.68 F1800.0 E117.423
G1 X-8.4 Y-9.12 Z0.68 F1800.0 E118.313
G1 X-8.8 Y-9.12 Z0.68 F1800.0 E118.333
G1 X-8.8 Y9.12 Z0.68 F1800.0 E119.224
G1 F798.0
G1 E118.724
G1 F1800.0
M103
G1 X0.4 Y9.12 Z0.68 F3000.0
G1 F798.0
G1 E119.024
G1 F3000.0
M101
G1 X0.4 Y-9.12 Z0.68 F1800.0 E119.915
G1 X0.8 Y-9.12 Z0.68 F1800.0 E119.934
G1 X0.8 Y9.12 Z0.68 F1800.0 E120.825
G1 X1.2 Y9.12 Z0.68 F1800.0 E120.845
G1 X1.2 Y-9.12 Z0.68 F1800.0 E121.735
G1 X1.6 Y-9.12 Z0.68 F1800.0 E121.755
G1 X1.6 Y9.12 Z0.68 F1800.0 E122.646
G1 X2.0 Y9.12 Z0.68 F1800.0 E122.665
G1 X2.0 Y-9.12 Z0.68 F1800.0 E123.556
G1 X2.4 Y-9.12 Z0.68 F1800.0 E123.576
G1 X2.4 Y9.12 Z0.68 F1800.0 E124.467
G1 X2.8 Y9.12 Z0.68 F1800.0 E124.486
G1 X2.8 Y-9.12 Z0.68 F1800.0 E125.377
G1 X3.2 Y-9.12 Z0.68 F1800.0 E125.396
G1 X3.2 Y9.12 Z0.68 F1800.0 E126.287
G1 X3.6 Y9.12 Z0.68 F1800.0 E126.307
G1 X3.6 Y-9.12 Z0.68 F1800.0 E127.198
G1 X4.0 Y-9.12 Z0.68 F1800.0 E127.217
G1 X4.0 Y9.12 Z0.68 F1800.0 E128.108
G1 X4.4 Y9.12 Z0.68 F1800.0 E128.128
G1 X4.4 Y-9.12 Z0.68 F1800.0 E129.018
G1 X4.8 Y-9.12 Z0.68 F1800.0 E129.038
G1 X4.8 Y9.12 Z0.68 F1800.0 E129.929
G1 X5.2 Y9.12 Z0.68 F1800.0 E129.948
G1 X5.2 Y-9.12 Z0.68 F1800.0 E130.839
G1 X5.6 Y-9.12 Z0.68 F1800.0 E130.859
G1 X5.6 Y9.12 Z0.68 F1800.0 E131.75
G1 X6.0 Y9.12 Z0.68 F1800.0 E131.769
G1 X6.0 Y-9.12 Z0.68 F1800.0 E132.66
G1 X6.4 Y-9.12 Z0.68 F1800.0 E132.679
G1 X6.4 Y9.12 Z0.68 F1800.0 E133.57
G1 X6.8 Y9.12 Z0.68 F1800.0 E133.59
G1 X6.8 Y-9.12 Z0.68 F1800.0 E134.481
G1 X7.2 Y-9.12 Z0.68 F1800.0 E134.5
G1 X7.2 Y9.12 Z0.68 F1800.0 E135.391
G1 X7.6 Y9.12 Z0.68 F1800.0 E135.411
G1 X7.6 Y-9.12 Z0.68 F1800.0 E136.301
G1 X8.0 Y-9.12 Z0.68 F1800.0 E136.321
G1 X8.0 Y9.12 Z0.68 F1800.0 E137.212
G1 X8.4 Y9.12 Z0.68 F1800.0 E137.231
G1 X8.4 Y-9.12 Z0.68 F1800.0 E138.122
G1 X8.8 Y-9.12 Z0.68 F1800.0 E138.142
G1 X8.8 Y9.12 Z0.68 F1800.0 E139.032
G1 F798.0
G1 E138.532
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P14 (display progress)
(<layer> 0.945 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z0.945 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z0.945 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z0.945 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z0.945 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.28 Z0.94 F3000.0
G1 F798.0
G1 E138.832
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z0.94 F1800.0 E138.838
G1 X9.4 Y-9.4 Z0.94 F1800.0 E139.757
G1 X9.4 Y9.4 Z0.94 F1800.0 E140.675
G1 X-9.4 Y9.4 Z0.94 F1800.0 E141.593
G1 X-9.4 Y-9.28 Z0.94 F1800.0 E142.505
G1 F798.0
G1 E142.505
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.28 Z0.94 F3000.0
G1 F798.0
G1 E142.505
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z0.94 F900.0 E142.511
G1 X-9.8 Y-9.8 Z0.94 F900.0 E142.531
G1 X9.8 Y-9.8 Z0.94 F900.0 E143.488
G1 X9.8 Y9.8 Z0.94 F900.0 E144.445
G1 X-9.8 Y9.8 Z0.94 F900.0 E145.402
G1 X-9.8 Y-9.28 Z0.94 F900.0 E146.334
G1 F798.0
G1 E146.279
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z0.945 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z0.945 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z0.945 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z0.945 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z0.94 F3000.0
G1 F798.0
G1 E146.312
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z0.94 F1800.0 E146.507
G1 X9.12 Y-4.4 Z0.94 F1800.0 E147.398
G1 X9.12 Y-8.8 Z0.94 F1800.0 E147.613
G1 X-9.12 Y-8.8 Z0.94 F1800.0 E148.504
G1 F798.0
G1 E148.004
G1 F1800.0
M103
G1 X9.12 Y7.2 Z0.94 F3000.0
G1 F798.0
G1 E148.304
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z0.94 F1800.0 E148.851
G1 X5.86 Y-4.0 Z0.94 F1800.0 E149.01
G1 X2.14 Y-1.33 Z0.94 F1800.0 E149.234
G1 X1.86 Y-1.33 Z0.94 F1800.0 E149.248
G1 X-1.86 Y-4.0 Z0.94 F1800.0 E149.471
G1 X-2.14 Y-4.0 Z0.94 F1800.0 E149.485
G1 X-5.86 Y-1.33 Z0.94 F1800.0 E149.708
G1 X-6.14 Y-1.33 Z0.94 F1800.0 E149.722
G1 X-9.12 Y-4.0 Z0.94 F1800.0 E149.917
G1 X-9.12 Y7.2 Z0.94 F1800.0 E150.464
G1 F798.0
G1 E150.464
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z0.94 F3000.0
G1 F798.0
G1 E150.464
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z0.94 F1800.0 E150.484
G1 X-6.14 Y4.0 Z0.94 F1800.0 E150.712
G1 X2.14 Y4.0 Z0.94 F1800.0 E151.116
G1 X5.86 Y6.67 Z0.94 F1800.0 E151.34
G1 X6.14 Y6.67 Z0.94 F1800.0 E151.354
G1 X9.12 Y7.6 Z0.94 F1800.0 E151.506
G1 X9.12 Y8.8 Z0.94 F1800.0 E151.565
G1 X-1.86 Y6.67 Z0.94 F1800.0 E152.111
G1 X-2.14 Y6.67 Z0.94 F1800.0 E152.125
G1 X-9.12 Y8.4 Z0.94 F1800.0 E152.476
G1 X-9.12 Y8.8 Z0.94 F1800.0 E152.496
G1 F798.0
G1 E151.996
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P16 (display progress)
(<layer> 1.215 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z1.215 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z1.215 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z1.215 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z1.215 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-8.97 Z1.22 F3000.0
G1 F798.0
G1 E152.296
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z1.22 F1800.0 E152.316
G1 X9.4 Y-9.4 Z1.22 F1800.0 E153.235
G1 X9.4 Y9.4 Z1.22 F1800.0 E154.153
G1 X-9.4 Y9.4 Z1.22 F1800.0 E155.071
G1 X-9.4 Y-8.97 Z1.22 F1800.0 E155.968
G1 F798.0
G1 E155.968
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-8.97 Z1.22 F3000.0
G1 F798.0
G1 E155.968
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z1.22 F900.0 E155.989
G1 X-9.8 Y-9.8 Z1.22 F900.0 E156.009
G1 X9.8 Y-9.8 Z1.22 F900.0 E156.966
G1 X9.8 Y9.8 Z1.22 F900.0 E157.923
G1 X-9.8 Y9.8 Z1.22 F900.0 E158.88
G1 X-9.8 Y-8.97 Z1.22 F900.0 E159.797
G1 F798.0
G1 E159.297
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z1.215 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z1.215 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z1.215 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z1.215 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z1.22 F3000.0
G1 F798.0
G1 E159.597
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z1.22 F1800.0 E159.773
G1 X-2.13 Y-4.0 Z1.22 F1800.0 E160.031
G1 X-5.87 Y-1.33 Z1.22 F1800.0 E160.256
G1 X-5.87 Y4.0 Z1.22 F1800.0 E160.517
G1 X-2.13 Y6.67 Z1.22 F1800.0 E160.741
G1 X-0.8 Y9.12 Z1.22 F1800.0 E160.877
G1 X-4.4 Y9.12 Z1.22 F1800.0 E161.053
G1 F798.0
G1 E160.553
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z1.22 F3000.0
G1 F798.0
G1 E160.853
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z1.22 F1800.0 E161.029
G1 X-6.13 Y4.0 Z1.22 F1800.0 E161.287
G1 X-6.13 Y-1.33 Z1.22 F1800.0 E161.548
G1 X-4.8 Y-9.12 Z1.22 F1800.0 E161.934
G1 X-8.8 Y-9.12 Z1.22 F1800.0 E162.129
G1 X-8.8 Y9.12 Z1.22 F1800.0 E163.02
G1 F798.0
G1 E162.52
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z1.22 F3000.0
G1 F798.0
G1 E162.82
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z1.22 F1800.0 E163.015
G1 X-1.87 Y-4.0 Z1.22 F1800.0 E163.275
G1 X1.87 Y-1.33 Z1.22 F1800.0 E163.5
G1 X1.87 Y4.0 Z1.22 F1800.0 E163.761
G1 X-1.87 Y6.67 Z1.22 F1800.0 E163.985
G1 X-0.4 Y9.12 Z1.22 F1800.0 E164.125
G1 X7.2 Y9.12 Z1.22 F1800.0 E164.496
G1 X5.87 Y6.67 Z1.22 F1800.0 E164.632
G1 X2.13 Y4.0 Z1.22 F1800.0 E164.857
G1 X2.13 Y-1.33 Z1.22 F1800.0 E165.117
G1 X5.87 Y-4.0 Z1.22 F1800.0 E165.342
G1 X7.2 Y-9.12 Z1.22 F1800.0 E165.6
G1 X4.0 Y-9.12 Z1.22 F1800.0 E165.757
G1 F798.0
G1 E165.257
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z1.22 F3000.0
G1 F798.0
G1 E165.557
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z1.22 F1800.0 E165.596
G1 X6.13 Y-4.0 Z1.22 F1800.0 E165.856
G1 X6.13 Y6.67 Z1.22 F1800.0 E166.377
G1 X7.6 Y9.12 Z1.22 F1800.0 E166.517
G1 X8.8 Y9.12 Z1.22 F1800.0 E166.575
G1 X8.8 Y-9.12 Z1.22 F1800.0 E167.466
G1 F798.0
G1 E166.966
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P19 (display progress)
(<layer> 1.485 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z1.485 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z1.485 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z1.485 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z1.485 </boundaryPoint>)
(<loop> outer )
G1 X-9.33 Y-9.4 Z1.49 F3000.0
G1 F798.0
G1 E167.266
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z1.49 F1800.0 E168.181
G1 X9.4 Y9.4 Z1.49 F1800.0 E169.099
G1 X-9.4 Y9.4 Z1.49 F1800.0 E170.017
G1 X-9.4 Y-9.4 Z1.49 F1800.0 E170.936
G1 X-9.33 Y-9.4 Z1.49 F1800.0 E170.939
G1 F798.0
G1 E170.939
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.47 Z1.49 F3000.0
G1 F798.0
G1 E170.939
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z1.49 F900.0 E170.955
G1 X9.8 Y-9.8 Z1.49 F900.0 E171.912
G1 X9.8 Y9.8 Z1.49 F900.0 E172.87
G1 X-9.8 Y9.8 Z1.49 F900.0 E173.827
G1 X-9.8 Y-9.4 Z1.49 F900.0 E174.765
G1 X-9.8 Y-9.47 Z1.49 F900.0 E174.768
G1 F798.0
G1 E174.635
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z1.485 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z1.485 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z1.485 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z1.485 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z1.49 F3000.0
G1 F798.0
G1 E174.715
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z1.49 F1800.0 E174.91
G1 X9.12 Y-4.4 Z1.49 F1800.0 E175.801
G1 X9.12 Y-8.8 Z1.49 F1800.0 E176.016
G1 X-9.12 Y-8.8 Z1.49 F1800.0 E176.907
G1 F798.0
G1 E176.407
G1 F1800.0
M103
G1 X9.12 Y7.2 Z1.49 F3000.0
G1 F798.0
G1 E176.707
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z1.49 F1800.0 E177.254
G1 X5.86 Y-4.0 Z1.49 F1800.0 E177.413
G1 X2.14 Y-1.33 Z1.49 F1800.0 E177.637
G1 X1.86 Y-1.33 Z1.49 F1800.0 E177.65
G1 X-1.86 Y-4.0 Z1.49 F1800.0 E177.874
G1 X-2.14 Y-4.0 Z1.49 F1800.0 E177.887
G1 X-5.86 Y-1.33 Z1.49 F1800.0 E178.111
G1 X-6.14 Y-1.33 Z1.49 F1800.0 E178.125
G1 X-9.12 Y-4.0 Z1.49 F1800.0 E178.32
G1 X-9.12 Y7.2 Z1.49 F1800.0 E178.867
G1 F798.0
G1 E178.867
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z1.49 F3000.0
G1 F798.0
G1 E178.867
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z1.49 F1800.0 E178.887
G1 X-6.14 Y4.0 Z1.49 F1800.0 E179.115
G1 X2.14 Y4.0 Z1.49 F1800.0 E179.519
G1 X5.86 Y6.67 Z1.49 F1800.0 E179.743
G1 X6.14 Y6.67 Z1.49 F1800.0 E179.756
G1 X9.12 Y7.6 Z1.49 F1800.0 E179.909
G1 X9.12 Y8.8 Z1.49 F1800.0 E179.968
G1 X-1.86 Y6.67 Z1.49 F1800.0 E180.514
G1 X-2.14 Y6.67 Z1.49 F1800.0 E180.527
G1 X-9.12 Y8.4 Z1.49 F1800.0 E180.879
G1 X-9.12 Y8.8 Z1.49 F1800.0 E180.898
G1 F798.0
G1 E180.398
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P21 (display progress)
(<layer> 1.755 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z1.755 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z1.755 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z1.755 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z1.755 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.16 Z1.75 F3000.0
G1 F798.0
G1 E180.698
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z1.75 F1800.0 E180.71
G1 X9.4 Y-9.4 Z1.75 F1800.0 E181.628
G1 X9.4 Y9.4 Z1.75 F1800.0 E182.546
G1 X-9.4 Y9.4 Z1.75 F1800.0 E183.465
G1 X-9.4 Y-9.16 Z1.75 F1800.0 E184.371
G1 F798.0
G1 E184.371
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.16 Z1.75 F3000.0
G1 F798.0
G1 E184.371
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z1.75 F900.0 E184.383
G1 X-9.8 Y-9.8 Z1.75 F900.0 E184.402
G1 X9.8 Y-9.8 Z1.75 F900.0 E185.359
G1 X9.8 Y9.8 Z1.75 F900.0 E186.317
G1 X-9.8 Y9.8 Z1.75 F900.0 E187.274
G1 X-9.8 Y-9.16 Z1.75 F900.0 E188.2
G1 F798.0
G1 E187.7
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z1.755 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z1.755 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z1.755 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z1.755 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z1.75 F3000.0
G1 F798.0
G1 E188.0
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z1.75 F1800.0 E188.176
G1 X-2.13 Y-4.0 Z1.75 F1800.0 E188.434
G1 X-5.87 Y-1.33 Z1.75 F1800.0 E188.659
G1 X-5.87 Y4.0 Z1.75 F1800.0 E188.919
G1 X-2.13 Y6.67 Z1.75 F1800.0 E189.144
G1 X-0.8 Y9.12 Z1.75 F1800.0 E189.28
G1 X-4.4 Y9.12 Z1.75 F1800.0 E189.456
G1 F798.0
G1 E188.956
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z1.75 F3000.0
G1 F798.0
G1 E189.256
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z1.75 F1800.0 E189.432
G1 X-6.13 Y4.0 Z1.75 F1800.0 E189.69
G1 X-6.13 Y-1.33 Z1.75 F1800.0 E189.951
G1 X-4.8 Y-9.12 Z1.75 F1800.0 E190.336
G1 X-8.8 Y-9.12 Z1.75 F1800.0 E190.532
G1 X-8.8 Y9.12 Z1.75 F1800.0 E191.423
G1 F798.0
G1 E190.923
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z1.75 F3000.0
G1 F798.0
G1 E191.223
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z1.75 F1800.0 E191.418
G1 X-1.87 Y-4.0 Z1.75 F1800.0 E191.678
G1 X1.87 Y-1.33 Z1.75 F1800.0 E191.903
G1 X1.87 Y4.0 Z1.75 F1800.0 E192.163
G1 X-1.87 Y6.67 Z1.75 F1800.0 E192.388
G1 X-0.4 Y9.12 Z1.75 F1800.0 E192.528
G1 X7.2 Y9.12 Z1.75 F1800.0 E192.899
G1 X5.87 Y6.67 Z1.75 F1800.0 E193.035
G1 X2.13 Y4.0 Z1.75 F1800.0 E193.26
G1 X2.13 Y-1.33 Z1.75 F1800.0 E193.52
G1 X5.87 Y-4.0 Z1.75 F1800.0 E193.745
G1 X7.2 Y-9.12 Z1.75 F1800.0 E194.003
G1 X4.0 Y-9.12 Z1.75 F1800.0 E194.159
G1 F798.0
G1 E193.659
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z1.75 F3000.0
G1 F798.0
G1 E193.959
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z1.75 F1800.0 E193.999
G1 X6.13 Y-4.0 Z1.75 F1800.0 E194.259
G1 X6.13 Y6.67 Z1.75 F1800.0 E194.78
G1 X7.6 Y9.12 Z1.75 F1800.0 E194.919
G1 X8.8 Y9.12 Z1.75 F1800.0 E194.978
G1 X8.8 Y-9.12 Z1.75 F1800.0 E195.869
G1 F798.0
G1 E195.369
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P24 (display progress)
(<layer> 2.025 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z2.025 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z2.025 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z2.025 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z2.025 </boundaryPoint>)
(<loop> outer )
G1 X-9.14 Y-9.4 Z2.02 F3000.0
G1 F798.0
G1 E195.669
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z2.02 F1800.0 E196.575
G1 X9.4 Y9.4 Z2.02 F1800.0 E197.493
G1 X-9.4 Y9.4 Z2.02 F1800.0 E198.411
G1 X-9.4 Y-9.4 Z2.02 F1800.0 E199.329
G1 X-9.14 Y-9.4 Z2.02 F1800.0 E199.342
G1 F798.0
G1 E199.342
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.65 Z2.02 F3000.0
G1 F798.0
G1 E199.342
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z2.02 F900.0 E199.349
G1 X9.8 Y-9.8 Z2.02 F900.0 E200.306
G1 X9.8 Y9.8 Z2.02 F900.0 E201.263
G1 X-9.8 Y9.8 Z2.02 F900.0 E202.22
G1 X-9.8 Y-9.4 Z2.02 F900.0 E203.158
G1 X-9.8 Y-9.65 Z2.02 F900.0 E203.171
G1 F798.0
G1 E202.957
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z2.025 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z2.025 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z2.025 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z2.025 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z2.02 F3000.0
G1 F798.0
G1 E203.085
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z2.02 F1800.0 E203.281
G1 X9.12 Y-4.4 Z2.02 F1800.0 E204.171
G1 X9.12 Y-8.8 Z2.02 F1800.0 E204.386
G1 X-9.12 Y-8.8 Z2.02 F1800.0 E205.277
G1 F798.0
G1 E204.777
G1 F1800.0
M103
G1 X9.12 Y7.2 Z2.02 F3000.0
G1 F798.0
G1 E205.077
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z2.02 F1800.0 E205.624
G1 X5.86 Y-4.0 Z2.02 F1800.0 E205.783
G1 X2.14 Y-1.33 Z2.02 F1800.0 E206.007
G1 X1.86 Y-1.33 Z2.02 F1800.0 E206.021
G1 X-1.86 Y-4.0 Z2.02 F1800.0 E206.244
G1 X-2.14 Y-4.0 Z2.02 F1800.0 E206.258
G1 X-5.86 Y-1.33 Z2.02 F1800.0 E206.481
G1 X-6.14 Y-1.33 Z2.02 F1800.0 E206.495
G1 X-9.12 Y-4.0 Z2.02 F1800.0 E206.69
G1 X-9.12 Y7.2 Z2.02 F1800.0 E207.237
G1 F798.0
G1 E207.237
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z2.02 F3000.0
G1 F798.0
G1 E207.237
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z2.02 F1800.0 E207.257
G1 X-6.14 Y4.0 Z2.02 F1800.0 E207.485
G1 X2.14 Y4.0 Z2.02 F1800.0 E207.89
G1 X5.86 Y6.67 Z2.02 F1800.0 E208.113
G1 X6.14 Y6.67 Z2.02 F1800.0 E208.127
G1 X9.12 Y7.6 Z2.02 F1800.0 E208.279
G1 X9.12 Y8.8 Z2.02 F1800.0 E208.338
G1 X-1.86 Y6.67 Z2.02 F1800.0 E208.884
G1 X-2.14 Y6.67 Z2.02 F1800.0 E208.898
G1 X-9.12 Y8.4 Z2.02 F1800.0 E209.249
G1 X-9.12 Y8.8 Z2.02 F1800.0 E209.269
G1 F798.0
G1 E208.769
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P26 (display progress)
(<layer> 2.295 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z2.295 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z2.295 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z2.295 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z2.295 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.35 Z2.29 F3000.0
G1 F798.0
G1 E209.069
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z2.29 F1800.0 E209.071
G1 X9.4 Y-9.4 Z2.29 F1800.0 E209.989
G1 X9.4 Y9.4 Z2.29 F1800.0 E210.907
G1 X-9.4 Y9.4 Z2.29 F1800.0 E211.826
G1 X-9.4 Y-9.35 Z2.29 F1800.0 E212.741
G1 F798.0
G1 E212.741
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.35 Z2.29 F3000.0
G1 F798.0
G1 E212.741
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z2.29 F900.0 E212.744
G1 X-9.8 Y-9.8 Z2.29 F900.0 E212.763
G1 X9.8 Y-9.8 Z2.29 F900.0 E213.721
G1 X9.8 Y9.8 Z2.29 F900.0 E214.678
G1 X-9.8 Y9.8 Z2.29 F900.0 E215.635
G1 X-9.8 Y-9.35 Z2.29 F900.0 E216.57
G1 F798.0
G1 E216.07
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z2.295 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z2.295 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z2.295 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z2.295 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z2.29 F3000.0
G1 F798.0
G1 E216.37
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z2.29 F1800.0 E216.546
G1 X-2.13 Y-4.0 Z2.29 F1800.0 E216.804
G1 X-5.87 Y-1.33 Z2.29 F1800.0 E217.029
G1 X-5.87 Y4.0 Z2.29 F1800.0 E217.29
G1 X-2.13 Y6.67 Z2.29 F1800.0 E217.514
G1 X-0.8 Y9.12 Z2.29 F1800.0 E217.65
G1 X-4.4 Y9.12 Z2.29 F1800.0 E217.826
G1 F798.0
G1 E217.326
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z2.29 F3000.0
G1 F798.0
G1 E217.626
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z2.29 F1800.0 E217.802
G1 X-6.13 Y4.0 Z2.29 F1800.0 E218.06
G1 X-6.13 Y-1.33 Z2.29 F1800.0 E218.321
G1 X-4.8 Y-9.12 Z2.29 F1800.0 E218.707
G1 X-8.8 Y-9.12 Z2.29 F1800.0 E218.902
G1 X-8.8 Y9.12 Z2.29 F1800.0 E219.793
G1 F798.0
G1 E219.293
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z2.29 F3000.0
G1 F798.0
G1 E219.593
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z2.29 F1800.0 E219.788
G1 X-1.87 Y-4.0 Z2.29 F1800.0 E220.048
G1 X1.87 Y-1.33 Z2.29 F1800.0 E220.273
G1 X1.87 Y4.0 Z2.29 F1800.0 E220.534
G1 X-1.87 Y6.67 Z2.29 F1800.0 E220.758
G1 X-0.4 Y9.12 Z2.29 F1800.0 E220.898
G1 X7.2 Y9.12 Z2.29 F1800.0 E221.269
G1 X5.87 Y6.67 Z2.29 F1800.0 E221.405
G1 X2.13 Y4.0 Z2.29 F1800.0 E221.63
G1 X2.13 Y-1.33 Z2.29 F1800.0 E221.89
G1 X5.87 Y-4.0 Z2.29 F1800.0 E222.115
G1 X7.2 Y-9.12 Z2.29 F1800.0 E222.373
G1 X4.0 Y-9.12 Z2.29 F1800.0 E222.53
G1 F798.0
G1 E222.03
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z2.29 F3000.0
G1 F798.0
G1 E222.33
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z2.29 F1800.0 E222.369
G1 X6.13 Y-4.0 Z2.29 F1800.0 E222.629
G1 X6.13 Y6.67 Z2.29 F1800.0 E223.15
G1 X7.6 Y9.12 Z2.29 F1800.0 E223.29
G1 X8.8 Y9.12 Z2.29 F1800.0 E223.348
G1 X8.8 Y-9.12 Z2.29 F1800.0 E224.239
G1 F798.0
G1 E223.739
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P28 (display progress)
(<layer> 2.565 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z2.565 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z2.565 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z2.565 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z2.565 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.04 Z2.56 F3000.0
G1 F798.0
G1 E224.039
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z2.56 F1800.0 E224.057
G1 X9.4 Y-9.4 Z2.56 F1800.0 E224.975
G1 X9.4 Y9.4 Z2.56 F1800.0 E225.893
G1 X-9.4 Y9.4 Z2.56 F1800.0 E226.811
G1 X-9.4 Y-9.04 Z2.56 F1800.0 E227.712
G1 F798.0
G1 E227.712
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.04 Z2.56 F3000.0
G1 F798.0
G1 E227.712
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z2.56 F900.0 E227.729
G1 X-9.8 Y-9.8 Z2.56 F900.0 E227.749
G1 X9.8 Y-9.8 Z2.56 F900.0 E228.706
G1 X9.8 Y9.8 Z2.56 F900.0 E229.663
G1 X-9.8 Y9.8 Z2.56 F900.0 E230.621
G1 X-9.8 Y-9.04 Z2.56 F900.0 E231.541
G1 F798.0
G1 E231.541
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z2.565 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z2.565 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z2.565 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z2.565 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z2.56 F3000.0
G1 F798.0
G1 E231.541
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z2.56 F1800.0 E231.736
G1 X9.12 Y-4.4 Z2.56 F1800.0 E232.627
G1 X9.12 Y-8.8 Z2.56 F1800.0 E232.842
G1 X-9.12 Y-8.8 Z2.56 F1800.0 E233.733
G1 F798.0
G1 E233.233
G1 F1800.0
M103
G1 X9.12 Y7.2 Z2.56 F3000.0
G1 F798.0
G1 E233.533
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z2.56 F1800.0 E234.08
G1 X5.86 Y-4.0 Z2.56 F1800.0 E234.239
G1 X2.14 Y-1.33 Z2.56 F1800.0 E234.463
G1 X1.86 Y-1.33 Z2.56 F1800.0 E234.476
G1 X-1.86 Y-4.0 Z2.56 F1800.0 E234.7
G1 X-2.14 Y-4.0 Z2.56 F1800.0 E234.714
G1 X-5.86 Y-1.33 Z2.56 F1800.0 E234.937
G1 X-6.14 Y-1.33 Z2.56 F1800.0 E234.951
G1 X-9.12 Y-4.0 Z2.56 F1800.0 E235.146
G1 X-9.12 Y7.2 Z2.56 F1800.0 E235.693
G1 F798.0
G1 E235.693
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z2.56 F3000.0
G1 F798.0
G1 E235.693
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z2.56 F1800.0 E235.713
G1 X-6.14 Y4.0 Z2.56 F1800.0 E235.941
G1 X2.14 Y4.0 Z2.56 F1800.0 E236.345
G1 X5.86 Y6.67 Z2.56 F1800.0 E236.569
G1 X6.14 Y6.67 Z2.56 F1800.0 E236.583
G1 X9.12 Y7.6 Z2.56 F1800.0 E236.735
G1 X9.12 Y8.8 Z2.56 F1800.0 E236.794
G1 X-1.86 Y6.67 Z2.56 F1800.0 E237.34
G1 X-2.14 Y6.67 Z2.56 F1800.0 E237.354
G1 X-9.12 Y8.4 Z2.56 F1800.0 E237.705
G1 X-9.12 Y8.8 Z2.56 F1800.0 E237.724
G1 F798.0
G1 E237.224
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P31 (display progress)
(<layer> 2.835 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z2.835 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z2.835 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z2.835 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z2.835 </boundaryPoint>)
(<loop> outer )
G1 X-9.26 Y-9.4 Z2.83 F3000.0
G1 F798.0
G1 E237.524
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z2.83 F1800.0 E238.436
G1 X9.4 Y9.4 Z2.83 F1800.0 E239.354
G1 X-9.4 Y9.4 Z2.83 F1800.0 E240.272
G1 X-9.4 Y-9.4 Z2.83 F1800.0 E241.19
G1 X-9.26 Y-9.4 Z2.83 F1800.0 E241.197
G1 F798.0
G1 E241.197
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.54 Z2.83 F3000.0
G1 F798.0
G1 E241.197
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z2.83 F900.0 E241.21
G1 X9.8 Y-9.8 Z2.83 F900.0 E242.167
G1 X9.8 Y9.8 Z2.83 F900.0 E243.124
G1 X-9.8 Y9.8 Z2.83 F900.0 E244.082
G1 X-9.8 Y-9.4 Z2.83 F900.0 E245.019
G1 X-9.8 Y-9.54 Z2.83 F900.0 E245.026
G1 F798.0
G1 E244.526
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z2.835 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z2.835 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z2.835 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z2.835 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z2.83 F3000.0
G1 F798.0
G1 E244.826
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z2.83 F1800.0 E245.002
G1 X-2.13 Y-4.0 Z2.83 F1800.0 E245.26
G1 X-5.87 Y-1.33 Z2.83 F1800.0 E245.485
G1 X-5.87 Y4.0 Z2.83 F1800.0 E245.745
G1 X-2.13 Y6.67 Z2.83 F1800.0 E245.97
G1 X-0.8 Y9.12 Z2.83 F1800.0 E246.106
G1 X-4.4 Y9.12 Z2.83 F1800.0 E246.282
G1 F798.0
G1 E245.782
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z2.83 F3000.0
G1 F798.0
G1 E246.082
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z2.83 F1800.0 E246.258
G1 X-6.13 Y4.0 Z2.83 F1800.0 E246.516
G1 X-6.13 Y-1.33 Z2.83 F1800.0 E246.777
G1 X-4.8 Y-9.12 Z2.83 F1800.0 E247.162
G1 X-8.8 Y-9.12 Z2.83 F1800.0 E247.358
G1 X-8.8 Y9.12 Z2.83 F1800.0 E248.249
G1 F798.0
G1 E247.749
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z2.83 F3000.0
G1 F798.0
G1 E248.049
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z2.83 F1800.0 E248.244
G1 X-1.87 Y-4.0 Z2.83 F1800.0 E248.504
G1 X1.87 Y-1.33 Z2.83 F1800.0 E248.729
G1 X1.87 Y4.0 Z2.83 F1800.0 E248.989
G1 X-1.87 Y6.67 Z2.83 F1800.0 E249.214
G1 X-0.4 Y9.12 Z2.83 F1800.0 E249.354
G1 X7.2 Y9.12 Z2.83 F1800.0 E249.725
G1 X5.87 Y6.67 Z2.83 F1800.0 E249.861
G1 X2.13 Y4.0 Z2.83 F1800.0 E250.086
G1 X2.13 Y-1.33 Z2.83 F1800.0 E250.346
G1 X5.87 Y-4.0 Z2.83 F1800.0 E250.571
G1 X7.2 Y-9.12 Z2.83 F1800.0 E250.829
G1 X4.0 Y-9.12 Z2.83 F1800.0 E250.986
G1 F798.0
G1 E250.486
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z2.83 F3000.0
G1 F798.0
G1 E250.786
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z2.83 F1800.0 E250.825
G1 X6.13 Y-4.0 Z2.83 F1800.0 E251.085
G1 X6.13 Y6.67 Z2.83 F1800.0 E251.606
G1 X7.6 Y9.12 Z2.83 F1800.0 E251.746
G1 X8.8 Y9.12 Z2.83 F1800.0 E251.804
G1 X8.8 Y-9.12 Z2.83 F1800.0 E252.695
G1 F798.0
G1 E252.195
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P33 (display progress)
(<layer> 3.105 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z3.105 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z3.105 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z3.105 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z3.105 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.23 Z3.1 F3000.0
G1 F798.0
G1 E252.495
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z3.1 F1800.0 E252.503
G1 X9.4 Y-9.4 Z3.1 F1800.0 E253.421
G1 X9.4 Y9.4 Z3.1 F1800.0 E254.34
G1 X-9.4 Y9.4 Z3.1 F1800.0 E255.258
G1 X-9.4 Y-9.23 Z3.1 F1800.0 E256.168
G1 F798.0
G1 E256.168
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.23 Z3.1 F3000.0
G1 F798.0
G1 E256.168
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z3.1 F900.0 E256.176
G1 X-9.8 Y-9.8 Z3.1 F900.0 E256.195
G1 X9.8 Y-9.8 Z3.1 F900.0 E257.153
G1 X9.8 Y9.8 Z3.1 F900.0 E258.11
G1 X-9.8 Y9.8 Z3.1 F900.0 E259.067
G1 X-9.8 Y-9.23 Z3.1 F900.0 E259.997
G1 F798.0
G1 E259.959
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z3.105 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z3.105 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z3.105 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z3.105 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z3.1 F3000.0
G1 F798.0
G1 E259.982
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z3.1 F1800.0 E260.177
G1 X9.12 Y-4.4 Z3.1 F1800.0 E261.068
G1 X9.12 Y-8.8 Z3.1 F1800.0 E261.283
G1 X-9.12 Y-8.8 Z3.1 F1800.0 E262.174
G1 F798.0
G1 E261.674
G1 F1800.0
M103
G1 X9.12 Y7.2 Z3.1 F3000.0
G1 F798.0
G1 E261.974
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z3.1 F1800.0 E262.521
G1 X5.86 Y-4.0 Z3.1 F1800.0 E262.68
G1 X2.14 Y-1.33 Z3.1 F1800.0 E262.903
G1 X1.86 Y-1.33 Z3.1 F1800.0 E262.917
G1 X-1.86 Y-4.0 Z3.1 F1800.0 E263.141
G1 X-2.14 Y-4.0 Z3.1 F1800.0 E263.154
G1 X-5.86 Y-1.33 Z3.1 F1800.0 E263.378
G1 X-6.14 Y-1.33 Z3.1 F1800.0 E263.392
G1 X-9.12 Y-4.0 Z3.1 F1800.0 E263.587
G1 X-9.12 Y7.2 Z3.1 F1800.0 E264.134
G1 F798.0
G1 E264.134
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z3.1 F3000.0
G1 F798.0
G1 E264.134
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z3.1 F1800.0 E264.153
G1 X-6.14 Y4.0 Z3.1 F1800.0 E264.382
G1 X2.14 Y4.0 Z3.1 F1800.0 E264.786
G1 X5.86 Y6.67 Z3.1 F1800.0 E265.01
G1 X6.14 Y6.67 Z3.1 F1800.0 E265.023
G1 X9.12 Y7.6 Z3.1 F1800.0 E265.176
G1 X9.12 Y8.8 Z3.1 F1800.0 E265.234
G1 X-1.86 Y6.67 Z3.1 F1800.0 E265.781
G1 X-2.14 Y6.67 Z3.1 F1800.0 E265.794
G1 X-9.12 Y8.4 Z3.1 F1800.0 E266.146
G1 X-9.12 Y8.8 Z3.1 F1800.0 E266.165
G1 F798.0
G1 E265.665
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P36 (display progress)
(<layer> 3.375 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z3.375 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z3.375 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z3.375 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z3.375 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-8.93 Z3.38 F3000.0
G1 F798.0
G1 E265.965
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z3.38 F1800.0 E265.988
G1 X9.4 Y-9.4 Z3.38 F1800.0 E266.906
G1 X9.4 Y9.4 Z3.38 F1800.0 E267.825
G1 X-9.4 Y9.4 Z3.38 F1800.0 E268.743
G1 X-9.4 Y-8.93 Z3.38 F1800.0 E269.638
G1 F798.0
G1 E269.638
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-8.93 Z3.38 F3000.0
G1 F798.0
G1 E269.638
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z3.38 F900.0 E269.661
G1 X-9.8 Y-9.8 Z3.38 F900.0 E269.68
G1 X9.8 Y-9.8 Z3.38 F900.0 E270.638
G1 X9.8 Y9.8 Z3.38 F900.0 E271.595
G1 X-9.8 Y9.8 Z3.38 F900.0 E272.552
G1 X-9.8 Y-8.93 Z3.38 F900.0 E273.467
G1 F798.0
G1 E272.967
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z3.375 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z3.375 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z3.375 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z3.375 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z3.38 F3000.0
G1 F798.0
G1 E273.267
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z3.38 F1800.0 E273.443
G1 X-2.13 Y-4.0 Z3.38 F1800.0 E273.701
G1 X-5.87 Y-1.33 Z3.38 F1800.0 E273.926
G1 X-5.87 Y4.0 Z3.38 F1800.0 E274.186
G1 X-2.13 Y6.67 Z3.38 F1800.0 E274.411
G1 X-0.8 Y9.12 Z3.38 F1800.0 E274.547
G1 X-4.4 Y9.12 Z3.38 F1800.0 E274.723
G1 F798.0
G1 E274.223
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z3.38 F3000.0
G1 F798.0
G1 E274.523
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z3.38 F1800.0 E274.699
G1 X-6.13 Y4.0 Z3.38 F1800.0 E274.957
G1 X-6.13 Y-1.33 Z3.38 F1800.0 E275.217
G1 X-4.8 Y-9.12 Z3.38 F1800.0 E275.603
G1 X-8.8 Y-9.12 Z3.38 F1800.0 E275.799
G1 X-8.8 Y9.12 Z3.38 F1800.0 E276.689
G1 F798.0
G1 E276.189
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z3.38 F3000.0
G1 F798.0
G1 E276.489
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z3.38 F1800.0 E276.685
G1 X-1.87 Y-4.0 Z3.38 F1800.0 E276.945
G1 X1.87 Y-1.33 Z3.38 F1800.0 E277.17
G1 X1.87 Y4.0 Z3.38 F1800.0 E277.43
G1 X-1.87 Y6.67 Z3.38 F1800.0 E277.655
G1 X-0.4 Y9.12 Z3.38 F1800.0 E277.795
G1 X7.2 Y9.12 Z3.38 F1800.0 E278.166
G1 X5.87 Y6.67 Z3.38 F1800.0 E278.302
G1 X2.13 Y4.0 Z3.38 F1800.0 E278.527
G1 X2.13 Y-1.33 Z3.38 F1800.0 E278.787
G1 X5.87 Y-4.0 Z3.38 F1800.0 E279.012
G1 X7.2 Y-9.12 Z3.38 F1800.0 E279.27
G1 X4.0 Y-9.12 Z3.38 F1800.0 E279.426
G1 F798.0
G1 E278.926
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z3.38 F3000.0
G1 F798.0
G1 E279.226
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z3.38 F1800.0 E279.265
G1 X6.13 Y-4.0 Z3.38 F1800.0 E279.526
G1 X6.13 Y6.67 Z3.38 F1800.0 E280.047
G1 X7.6 Y9.12 Z3.38 F1800.0 E280.186
G1 X8.8 Y9.12 Z3.38 F1800.0 E280.245
G1 X8.8 Y-9.12 Z3.38 F1800.0 E281.136
G1 F798.0
G1 E280.636
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P38 (display progress)
(<layer> 3.645 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z3.645 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z3.645 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z3.645 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z3.645 </boundaryPoint>)
(<loop> outer )
G1 X-9.38 Y-9.4 Z3.65 F3000.0
G1 F798.0
G1 E280.936
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z3.65 F1800.0 E281.853
G1 X9.4 Y9.4 Z3.65 F1800.0 E282.771
G1 X-9.4 Y9.4 Z3.65 F1800.0 E283.689
G1 X-9.4 Y-9.4 Z3.65 F1800.0 E284.607
G1 X-9.38 Y-9.4 Z3.65 F1800.0 E284.608
G1 F798.0
G1 E284.608
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.42 Z3.65 F3000.0
G1 F798.0
G1 E284.608
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z3.65 F900.0 E284.627
G1 X9.8 Y-9.8 Z3.65 F900.0 E285.584
G1 X9.8 Y9.8 Z3.65 F900.0 E286.541
G1 X-9.8 Y9.8 Z3.65 F900.0 E287.499
G1 X-9.8 Y-9.4 Z3.65 F900.0 E288.436
G1 X-9.8 Y-9.42 Z3.65 F900.0 E288.438
G1 F798.0
G1 E288.324
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z3.645 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z3.645 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z3.645 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z3.645 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z3.65 F3000.0
G1 F798.0
G1 E288.392
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z3.65 F1800.0 E288.587
G1 X9.12 Y-4.4 Z3.65 F1800.0 E289.478
G1 X9.12 Y-8.8 Z3.65 F1800.0 E289.693
G1 X-9.12 Y-8.8 Z3.65 F1800.0 E290.584
G1 F798.0
G1 E290.084
G1 F1800.0
M103
G1 X9.12 Y7.2 Z3.65 F3000.0
G1 F798.0
G1 E290.384
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z3.65 F1800.0 E290.931
G1 X5.86 Y-4.0 Z3.65 F1800.0 E291.09
G1 X2.14 Y-1.33 Z3.65 F1800.0 E291.314
G1 X1.86 Y-1.33 Z3.65 F1800.0 E291.327
G1 X-1.86 Y-4.0 Z3.65 F1800.0 E291.551
G1 X-2.14 Y-4.0 Z3.65 F1800.0 E291.565
G1 X-5.86 Y-1.33 Z3.65 F1800.0 E291.788
G1 X-6.14 Y-1.33 Z3.65 F1800.0 E291.802
G1 X-9.12 Y-4.0 Z3.65 F1800.0 E291.997
G1 X-9.12 Y7.2 Z3.65 F1800.0 E292.544
G1 F798.0
G1 E292.544
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z3.65 F3000.0
G1 F798.0
G1 E292.544
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z3.65 F1800.0 E292.564
G1 X-6.14 Y4.0 Z3.65 F1800.0 E292.792
G1 X2.14 Y4.0 Z3.65 F1800.0 E293.196
G1 X5.86 Y6.67 Z3.65 F1800.0 E293.42
G1 X6.14 Y6.67 Z3.65 F1800.0 E293.434
G1 X9.12 Y7.6 Z3.65 F1800.0 E293.586
G1 X9.12 Y8.8 Z3.65 F1800.0 E293.645
G1 X-1.86 Y6.67 Z3.65 F1800.0 E294.191
G1 X-2.14 Y6.67 Z3.65 F1800.0 E294.205
G1 X-9.12 Y8.4 Z3.65 F1800.0 E294.556
G1 X-9.12 Y8.8 Z3.65 F1800.0 E294.575
G1 F798.0
G1 E294.075
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P40 (display progress)
(<layer> 3.915 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z3.915 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z3.915 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z3.915 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z3.915 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.12 Z3.92 F3000.0
G1 F798.0
G1 E294.375
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z3.92 F1800.0 E294.389
G1 X9.4 Y-9.4 Z3.92 F1800.0 E295.307
G1 X9.4 Y9.4 Z3.92 F1800.0 E296.226
G1 X-9.4 Y9.4 Z3.92 F1800.0 E297.144
G1 X-9.4 Y-9.12 Z3.92 F1800.0 E298.048
G1 F798.0
G1 E298.048
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.12 Z3.92 F3000.0
G1 F798.0
G1 E298.048
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z3.92 F900.0 E298.062
G1 X-9.8 Y-9.8 Z3.92 F900.0 E298.082
G1 X9.8 Y-9.8 Z3.92 F900.0 E299.039
G1 X9.8 Y9.8 Z3.92 F900.0 E299.996
G1 X-9.8 Y9.8 Z3.92 F900.0 E300.953
G1 X-9.8 Y-9.12 Z3.92 F900.0 E301.877
G1 F798.0
G1 E301.377
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z3.915 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z3.915 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z3.915 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z3.915 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z3.92 F3000.0
G1 F798.0
G1 E301.677
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z3.92 F1800.0 E301.853
G1 X-2.13 Y-4.0 Z3.92 F1800.0 E302.111
G1 X-5.87 Y-1.33 Z3.92 F1800.0 E302.336
G1 X-5.87 Y4.0 Z3.92 F1800.0 E302.596
G1 X-2.13 Y6.67 Z3.92 F1800.0 E302.821
G1 X-0.8 Y9.12 Z3.92 F1800.0 E302.957
G1 X-4.4 Y9.12 Z3.92 F1800.0 E303.133
G1 F798.0
G1 E302.633
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z3.92 F3000.0
G1 F798.0
G1 E302.933
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z3.92 F1800.0 E303.109
G1 X-6.13 Y4.0 Z3.92 F1800.0 E303.367
G1 X-6.13 Y-1.33 Z3.92 F1800.0 E303.628
G1 X-4.8 Y-9.12 Z3.92 F1800.0 E304.013
G1 X-8.8 Y-9.12 Z3.92 F1800.0 E304.209
G1 X-8.8 Y9.12 Z3.92 F1800.0 E305.1
G1 F798.0
G1 E304.6
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z3.92 F3000.0
G1 F798.0
G1 E304.9
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z3.92 F1800.0 E305.095
G1 X-1.87 Y-4.0 Z3.92 F1800.0 E305.355
G1 X1.87 Y-1.33 Z3.92 F1800.0 E305.58
G1 X1.87 Y4.0 Z3.92 F1800.0 E305.84
G1 X-1.87 Y6.67 Z3.92 F1800.0 E306.065
G1 X-0.4 Y9.12 Z3.92 F1800.0 E306.205
G1 X7.2 Y9.12 Z3.92 F1800.0 E306.576
G1 X5.87 Y6.67 Z3.92 F1800.0 E306.712
G1 X2.13 Y4.0 Z3.92 F1800.0 E306.937
G1 X2.13 Y-1.33 Z3.92 F1800.0 E307.197
G1 X5.87 Y-4.0 Z3.92 F1800.0 E307.422
G1 X7.2 Y-9.12 Z3.92 F1800.0 E307.68
G1 X4.0 Y-9.12 Z3.92 F1800.0 E307.837
G1 F798.0
G1 E307.337
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z3.92 F3000.0
G1 F798.0
G1 E307.637
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z3.92 F1800.0 E307.676
G1 X6.13 Y-4.0 Z3.92 F1800.0 E307.936
G1 X6.13 Y6.67 Z3.92 F1800.0 E308.457
G1 X7.6 Y9.12 Z3.92 F1800.0 E308.597
G1 X8.8 Y9.12 Z3.92 F1800.0 E308.655
G1 X8.8 Y-9.12 Z3.92 F1800.0 E309.546
G1 F798.0
G1 E309.046
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P43 (display progress)
(<layer> 4.185 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z4.185 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z4.185 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z4.185 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z4.185 </boundaryPoint>)
(<loop> outer )
G1 X-9.19 Y-9.4 Z4.18 F3000.0
G1 F798.0
G1 E309.346
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z4.18 F1800.0 E310.254
G1 X9.4 Y9.4 Z4.18 F1800.0 E311.172
G1 X-9.4 Y9.4 Z4.18 F1800.0 E312.09
G1 X-9.4 Y-9.4 Z4.18 F1800.0 E313.008
G1 X-9.19 Y-9.4 Z4.18 F1800.0 E313.019
G1 F798.0
G1 E313.019
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.61 Z4.18 F3000.0
G1 F798.0
G1 E313.019
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z4.18 F900.0 E313.028
G1 X9.8 Y-9.8 Z4.18 F900.0 E313.985
G1 X9.8 Y9.8 Z4.18 F900.0 E314.943
G1 X-9.8 Y9.8 Z4.18 F900.0 E315.9
G1 X-9.8 Y-9.4 Z4.18 F900.0 E316.837
G1 X-9.8 Y-9.61 Z4.18 F900.0 E316.848
G1 F798.0
G1 E316.653
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z4.185 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z4.185 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z4.185 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z4.185 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z4.18 F3000.0
G1 F798.0
G1 E316.77
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z4.18 F1800.0 E316.965
G1 X9.12 Y-4.4 Z4.18 F1800.0 E317.856
G1 X9.12 Y-8.8 Z4.18 F1800.0 E318.071
G1 X-9.12 Y-8.8 Z4.18 F1800.0 E318.962
G1 F798.0
G1 E318.462
G1 F1800.0
M103
G1 X9.12 Y7.2 Z4.18 F3000.0
G1 F798.0
G1 E318.762
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z4.18 F1800.0 E319.309
G1 X5.86 Y-4.0 Z4.18 F1800.0 E319.468
G1 X2.14 Y-1.33 Z4.18 F1800.0 E319.692
G1 X1.86 Y-1.33 Z4.18 F1800.0 E319.705
G1 X-1.86 Y-4.0 Z4.18 F1800.0 E319.929
G1 X-2.14 Y-4.0 Z4.18 F1800.0 E319.943
G1 X-5.86 Y-1.33 Z4.18 F1800.0 E320.166
G1 X-6.14 Y-1.33 Z4.18 F1800.0 E320.18
G1 X-9.12 Y-4.0 Z4.18 F1800.0 E320.375
G1 X-9.12 Y7.2 Z4.18 F1800.0 E320.922
G1 F798.0
G1 E320.922
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z4.18 F3000.0
G1 F798.0
G1 E320.922
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z4.18 F1800.0 E320.942
G1 X-6.14 Y4.0 Z4.18 F1800.0 E321.17
G1 X2.14 Y4.0 Z4.18 F1800.0 E321.574
G1 X5.86 Y6.67 Z4.18 F1800.0 E321.798
G1 X6.14 Y6.67 Z4.18 F1800.0 E321.812
G1 X9.12 Y7.6 Z4.18 F1800.0 E321.964
G1 X9.12 Y8.8 Z4.18 F1800.0 E322.023
G1 X-1.86 Y6.67 Z4.18 F1800.0 E322.569
G1 X-2.14 Y6.67 Z4.18 F1800.0 E322.583
G1 X-9.12 Y8.4 Z4.18 F1800.0 E322.934
G1 X-9.12 Y8.8 Z4.18 F1800.0 E322.953
G1 F798.0
G1 E322.453
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P45 (display progress)
(<layer> 4.455 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z4.455 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z4.455 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z4.455 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z4.455 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.3 Z4.46 F3000.0
G1 F798.0
G1 E322.753
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z4.46 F1800.0 E322.758
G1 X9.4 Y-9.4 Z4.46 F1800.0 E323.676
G1 X9.4 Y9.4 Z4.46 F1800.0 E324.594
G1 X-9.4 Y9.4 Z4.46 F1800.0 E325.513
G1 X-9.4 Y-9.3 Z4.46 F1800.0 E326.426
G1 F798.0
G1 E326.426
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.3 Z4.46 F3000.0
G1 F798.0
G1 E326.426
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z4.46 F900.0 E326.431
G1 X-9.8 Y-9.8 Z4.46 F900.0 E326.45
G1 X9.8 Y-9.8 Z4.46 F900.0 E327.408
G1 X9.8 Y9.8 Z4.46 F900.0 E328.365
G1 X-9.8 Y9.8 Z4.46 F900.0 E329.322
G1 X-9.8 Y-9.3 Z4.46 F900.0 E330.255
G1 F798.0
G1 E329.755
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z4.455 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z4.455 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z4.455 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z4.455 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z4.46 F3000.0
G1 F798.0
G1 E330.055
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z4.46 F1800.0 E330.231
G1 X-2.13 Y-4.0 Z4.46 F1800.0 E330.489
G1 X-5.87 Y-1.33 Z4.46 F1800.0 E330.714
G1 X-5.87 Y4.0 Z4.46 F1800.0 E330.974
G1 X-2.13 Y6.67 Z4.46 F1800.0 E331.199
G1 X-0.8 Y9.12 Z4.46 F1800.0 E331.335
G1 X-4.4 Y9.12 Z4.46 F1800.0 E331.511
G1 F798.0
G1 E331.011
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z4.46 F3000.0
G1 F798.0
G1 E331.311
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z4.46 F1800.0 E331.487
G1 X-6.13 Y4.0 Z4.46 F1800.0 E331.745
G1 X-6.13 Y-1.33 Z4.46 F1800.0 E332.006
G1 X-4.8 Y-9.12 Z4.46 F1800.0 E332.392
G1 X-8.8 Y-9.12 Z4.46 F1800.0 E332.587
G1 X-8.8 Y9.12 Z4.46 F1800.0 E333.478
G1 F798.0
G1 E332.978
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z4.46 F3000.0
G1 F798.0
G1 E333.278
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z4.46 F1800.0 E333.473
G1 X-1.87 Y-4.0 Z4.46 F1800.0 E333.733
G1 X1.87 Y-1.33 Z4.46 F1800.0 E333.958
G1 X1.87 Y4.0 Z4.46 F1800.0 E334.218
G1 X-1.87 Y6.67 Z4.46 F1800.0 E334.443
G1 X-0.4 Y9.12 Z4.46 F1800.0 E334.583
G1 X7.2 Y9.12 Z4.46 F1800.0 E334.954
G1 X5.87 Y6.67 Z4.46 F1800.0 E335.09
G1 X2.13 Y4.0 Z4.46 F1800.0 E335.315
G1 X2.13 Y-1.33 Z4.46 F1800.0 E335.575
G1 X5.87 Y-4.0 Z4.46 F1800.0 E335.8
G1 X7.2 Y-9.12 Z4.46 F1800.0 E336.058
G1 X4.0 Y-9.12 Z4.46 F1800.0 E336.215
G1 F798.0
G1 E335.715
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z4.46 F3000.0
G1 F798.0
G1 E336.015
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z4.46 F1800.0 E336.054
G1 X6.13 Y-4.0 Z4.46 F1800.0 E336.314
G1 X6.13 Y6.67 Z4.46 F1800.0 E336.835
G1 X7.6 Y9.12 Z4.46 F1800.0 E336.975
G1 X8.8 Y9.12 Z4.46 F1800.0 E337.033
G1 X8.8 Y-9.12 Z4.46 F1800.0 E337.924
G1 F798.0
G1 E337.424
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P48 (display progress)
(<layer> 4.725 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z4.725 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z4.725 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z4.725 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z4.725 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.0 Z4.72 F3000.0
G1 F798.0
G1 E337.724
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z4.72 F1800.0 E337.744
G1 X9.4 Y-9.4 Z4.72 F1800.0 E338.662
G1 X9.4 Y9.4 Z4.72 F1800.0 E339.58
G1 X-9.4 Y9.4 Z4.72 F1800.0 E340.498
G1 X-9.4 Y-9.0 Z4.72 F1800.0 E341.397
G1 F798.0
G1 E341.397
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.0 Z4.72 F3000.0
G1 F798.0
G1 E341.397
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z4.72 F900.0 E341.416
G1 X-9.8 Y-9.8 Z4.72 F900.0 E341.436
G1 X9.8 Y-9.8 Z4.72 F900.0 E342.393
G1 X9.8 Y9.8 Z4.72 F900.0 E343.35
G1 X-9.8 Y9.8 Z4.72 F900.0 E344.308
G1 X-9.8 Y-9.0 Z4.72 F900.0 E345.226
G1 F798.0
G1 E345.226
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z4.725 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z4.725 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z4.725 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z4.725 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z4.72 F3000.0
G1 F798.0
G1 E345.226
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z4.72 F1800.0 E345.421
G1 X9.12 Y-4.4 Z4.72 F1800.0 E346.312
G1 X9.12 Y-8.8 Z4.72 F1800.0 E346.527
G1 X-9.12 Y-8.8 Z4.72 F1800.0 E347.418
G1 F798.0
G1 E346.918
G1 F1800.0
M103
G1 X9.12 Y7.2 Z4.72 F3000.0
G1 F798.0
G1 E347.218
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z4.72 F1800.0 E347.765
G1 X5.86 Y-4.0 Z4.72 F1800.0 E347.924
G1 X2.14 Y-1.33 Z4.72 F1800.0 E348.148
G1 X1.86 Y-1.33 Z4.72 F1800.0 E348.161
G1 X-1.86 Y-4.0 Z4.72 F1800.0 E348.385
G1 X-2.14 Y-4.0 Z4.72 F1800.0 E348.398
G1 X-5.86 Y-1.33 Z4.72 F1800.0 E348.622
G1 X-6.14 Y-1.33 Z4.72 F1800.0 E348.636
G1 X-9.12 Y-4.0 Z4.72 F1800.0 E348.831
G1 X-9.12 Y7.2 Z4.72 F1800.0 E349.378
G1 F798.0
G1 E349.378
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z4.72 F3000.0
G1 F798.0
G1 E349.378
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z4.72 F1800.0 E349.397
G1 X-6.14 Y4.0 Z4.72 F1800.0 E349.626
G1 X2.14 Y4.0 Z4.72 F1800.0 E350.03
G1 X5.86 Y6.67 Z4.72 F1800.0 E350.254
G1 X6.14 Y6.67 Z4.72 F1800.0 E350.267
G1 X9.12 Y7.6 Z4.72 F1800.0 E350.42
G1 X9.12 Y8.8 Z4.72 F1800.0 E350.478
G1 X-1.86 Y6.67 Z4.72 F1800.0 E351.025
G1 X-2.14 Y6.67 Z4.72 F1800.0 E351.038
G1 X-9.12 Y8.4 Z4.72 F1800.0 E351.39
G1 X-9.12 Y8.8 Z4.72 F1800.0 E351.409
G1 F798.0
G1 E350.909
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P50 (display progress)
(<layer> 4.995 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z4.995 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z4.995 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z4.995 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z4.995 </boundaryPoint>)
(<loop> outer )
G1 X-9.31 Y-9.4 Z5.0 F3000.0
G1 F798.0
G1 E351.209
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z5.0 F1800.0 E352.123
G1 X9.4 Y9.4 Z5.0 F1800.0 E353.041
G1 X-9.4 Y9.4 Z5.0 F1800.0 E353.959
G1 X-9.4 Y-9.4 Z5.0 F1800.0 E354.877
G1 X-9.31 Y-9.4 Z5.0 F1800.0 E354.882
G1 F798.0
G1 E354.882
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.49 Z5.0 F3000.0
G1 F798.0
G1 E354.882
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z5.0 F900.0 E354.897
G1 X9.8 Y-9.8 Z5.0 F900.0 E355.854
G1 X9.8 Y9.8 Z5.0 F900.0 E356.811
G1 X-9.8 Y9.8 Z5.0 F900.0 E357.769
G1 X-9.8 Y-9.4 Z5.0 F900.0 E358.706
G1 X-9.8 Y-9.49 Z5.0 F900.0 E358.711
G1 F798.0
G1 E358.211
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z4.995 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z4.995 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z4.995 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z4.995 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z5.0 F3000.0
G1 F798.0
G1 E358.511
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z5.0 F1800.0 E358.687
G1 X-2.13 Y-4.0 Z5.0 F1800.0 E358.945
G1 X-5.87 Y-1.33 Z5.0 F1800.0 E359.17
G1 X-5.87 Y4.0 Z5.0 F1800.0 E359.43
G1 X-2.13 Y6.67 Z5.0 F1800.0 E359.655
G1 X-0.8 Y9.12 Z5.0 F1800.0 E359.791
G1 X-4.4 Y9.12 Z5.0 F1800.0 E359.967
G1 F798.0
G1 E359.467
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z5.0 F3000.0
G1 F798.0
G1 E359.767
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z5.0 F1800.0 E359.943
G1 X-6.13 Y4.0 Z5.0 F1800.0 E360.201
G1 X-6.13 Y-1.33 Z5.0 F1800.0 E360.462
G1 X-4.8 Y-9.12 Z5.0 F1800.0 E360.847
G1 X-8.8 Y-9.12 Z5.0 F1800.0 E361.043
G1 X-8.8 Y9.12 Z5.0 F1800.0 E361.933
G1 F798.0
G1 E361.433
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z5.0 F3000.0
G1 F798.0
G1 E361.733
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z5.0 F1800.0 E361.929
G1 X-1.87 Y-4.0 Z5.0 F1800.0 E362.189
G1 X1.87 Y-1.33 Z5.0 F1800.0 E362.414
G1 X1.87 Y4.0 Z5.0 F1800.0 E362.674
G1 X-1.87 Y6.67 Z5.0 F1800.0 E362.899
G1 X-0.4 Y9.12 Z5.0 F1800.0 E363.039
G1 X7.2 Y9.12 Z5.0 F1800.0 E363.41
G1 X5.87 Y6.67 Z5.0 F1800.0 E363.546
G1 X2.13 Y4.0 Z5.0 F1800.0 E363.771
G1 X2.13 Y-1.33 Z5.0 F1800.0 E364.031
G1 X5.87 Y-4.0 Z5.0 F1800.0 E364.256
G1 X7.2 Y-9.12 Z5.0 F1800.0 E364.514
G1 X4.0 Y-9.12 Z5.0 F1800.0 E364.67
G1 F798.0
G1 E364.17
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z5.0 F3000.0
G1 F798.0
G1 E364.47
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z5.0 F1800.0 E364.509
G1 X6.13 Y-4.0 Z5.0 F1800.0 E364.77
G1 X6.13 Y6.67 Z5.0 F1800.0 E365.291
G1 X7.6 Y9.12 Z5.0 F1800.0 E365.43
G1 X8.8 Y9.12 Z5.0 F1800.0 E365.489
G1 X8.8 Y-9.12 Z5.0 F1800.0 E366.38
G1 F798.0
G1 E365.88
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P53 (display progress)
(<layer> 5.265 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z5.265 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z5.265 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z5.265 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z5.265 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.19 Z5.26 F3000.0
G1 F798.0
G1 E366.18
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z5.26 F1800.0 E366.19
G1 X9.4 Y-9.4 Z5.26 F1800.0 E367.108
G1 X9.4 Y9.4 Z5.26 F1800.0 E368.027
G1 X-9.4 Y9.4 Z5.26 F1800.0 E368.945
G1 X-9.4 Y-9.19 Z5.26 F1800.0 E369.853
G1 F798.0
G1 E369.853
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.19 Z5.26 F3000.0
G1 F798.0
G1 E369.853
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z5.26 F900.0 E369.863
G1 X-9.8 Y-9.8 Z5.26 F900.0 E369.882
G1 X9.8 Y-9.8 Z5.26 F900.0 E370.84
G1 X9.8 Y9.8 Z5.26 F900.0 E371.797
G1 X-9.8 Y9.8 Z5.26 F900.0 E372.754
G1 X-9.8 Y-9.19 Z5.26 F900.0 E373.682
G1 F798.0
G1 E373.661
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z5.265 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z5.265 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z5.265 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z5.265 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z5.26 F3000.0
G1 F798.0
G1 E373.673
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z5.26 F1800.0 E373.869
G1 X9.12 Y-4.4 Z5.26 F1800.0 E374.759
G1 X9.12 Y-8.8 Z5.26 F1800.0 E374.974
G1 X-9.12 Y-8.8 Z5.26 F1800.0 E375.865
G1 F798.0
G1 E375.365
G1 F1800.0
M103
G1 X9.12 Y7.2 Z5.26 F3000.0
G1 F798.0
G1 E375.665
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z5.26 F1800.0 E376.212
G1 X5.86 Y-4.0 Z5.26 F1800.0 E376.371
G1 X2.14 Y-1.33 Z5.26 F1800.0 E376.595
G1 X1.86 Y-1.33 Z5.26 F1800.0 E376.609
G1 X-1.86 Y-4.0 Z5.26 F1800.0 E376.832
G1 X-2.14 Y-4.0 Z5.26 F1800.0 E376.846
G1 X-5.86 Y-1.33 Z5.26 F1800.0 E377.069
G1 X-6.14 Y-1.33 Z5.26 F1800.0 E377.083
G1 X-9.12 Y-4.0 Z5.26 F1800.0 E377.278
G1 X-9.12 Y7.2 Z5.26 F1800.0 E377.825
G1 F798.0
G1 E377.825
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z5.26 F3000.0
G1 F798.0
G1 E377.825
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z5.26 F1800.0 E377.845
G1 X-6.14 Y4.0 Z5.26 F1800.0 E378.073
G1 X2.14 Y4.0 Z5.26 F1800.0 E378.478
G1 X5.86 Y6.67 Z5.26 F1800.0 E378.701
G1 X6.14 Y6.67 Z5.26 F1800.0 E378.715
G1 X9.12 Y7.6 Z5.26 F1800.0 E378.867
G1 X9.12 Y8.8 Z5.26 F1800.0 E378.926
G1 X-1.86 Y6.67 Z5.26 F1800.0 E379.472
G1 X-2.14 Y6.67 Z5.26 F1800.0 E379.486
G1 X-9.12 Y8.4 Z5.26 F1800.0 E379.837
G1 X-9.12 Y8.8 Z5.26 F1800.0 E379.857
G1 F798.0
G1 E379.357
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P55 (display progress)
(<layer> 5.535 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z5.535 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z5.535 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z5.535 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z5.535 </boundaryPoint>)
(<loop> outer )
G1 X-9.12 Y-9.4 Z5.54 F3000.0
G1 F798.0
G1 E379.657
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z5.54 F1800.0 E380.561
G1 X9.4 Y9.4 Z5.54 F1800.0 E381.479
G1 X-9.4 Y9.4 Z5.54 F1800.0 E382.397
G1 X-9.4 Y-9.4 Z5.54 F1800.0 E383.316
G1 X-9.12 Y-9.4 Z5.54 F1800.0 E383.329
G1 F798.0
G1 E383.329
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.68 Z5.54 F3000.0
G1 F798.0
G1 E383.329
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z5.54 F900.0 E383.335
G1 X9.8 Y-9.8 Z5.54 F900.0 E384.292
G1 X9.8 Y9.8 Z5.54 F900.0 E385.25
G1 X-9.8 Y9.8 Z5.54 F900.0 E386.207
G1 X-9.8 Y-9.4 Z5.54 F900.0 E387.145
G1 X-9.8 Y-9.68 Z5.54 F900.0 E387.158
G1 F798.0
G1 E386.658
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z5.535 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z5.535 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z5.535 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z5.535 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z5.54 F3000.0
G1 F798.0
G1 E386.958
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z5.54 F1800.0 E387.134
G1 X-2.13 Y-4.0 Z5.54 F1800.0 E387.393
G1 X-5.87 Y-1.33 Z5.54 F1800.0 E387.617
G1 X-5.87 Y4.0 Z5.54 F1800.0 E387.878
G1 X-2.13 Y6.67 Z5.54 F1800.0 E388.102
G1 X-0.8 Y9.12 Z5.54 F1800.0 E388.239
G1 X-4.4 Y9.12 Z5.54 F1800.0 E388.414
G1 F798.0
G1 E387.914
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z5.54 F3000.0
G1 F798.0
G1 E388.214
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z5.54 F1800.0 E388.39
G1 X-6.13 Y4.0 Z5.54 F1800.0 E388.649
G1 X-6.13 Y-1.33 Z5.54 F1800.0 E388.909
G1 X-4.8 Y-9.12 Z5.54 F1800.0 E389.295
G1 X-8.8 Y-9.12 Z5.54 F1800.0 E389.49
G1 X-8.8 Y9.12 Z5.54 F1800.0 E390.381
G1 F798.0
G1 E389.881
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z5.54 F3000.0
G1 F798.0
G1 E390.181
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z5.54 F1800.0 E390.376
G1 X-1.87 Y-4.0 Z5.54 F1800.0 E390.637
G1 X1.87 Y-1.33 Z5.54 F1800.0 E390.861
G1 X1.87 Y4.0 Z5.54 F1800.0 E391.122
G1 X-1.87 Y6.67 Z5.54 F1800.0 E391.346
G1 X-0.4 Y9.12 Z5.54 F1800.0 E391.486
G1 X7.2 Y9.12 Z5.54 F1800.0 E391.857
G1 X5.87 Y6.67 Z5.54 F1800.0 E391.993
G1 X2.13 Y4.0 Z5.54 F1800.0 E392.218
G1 X2.13 Y-1.33 Z5.54 F1800.0 E392.479
G1 X5.87 Y-4.0 Z5.54 F1800.0 E392.703
G1 X7.2 Y-9.12 Z5.54 F1800.0 E392.962
G1 X4.0 Y-9.12 Z5.54 F1800.0 E393.118
G1 F798.0
G1 E392.618
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z5.54 F3000.0
G1 F798.0
G1 E392.918
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z5.54 F1800.0 E392.957
G1 X6.13 Y-4.0 Z5.54 F1800.0 E393.217
G1 X6.13 Y6.67 Z5.54 F1800.0 E393.738
G1 X7.6 Y9.12 Z5.54 F1800.0 E393.878
G1 X8.8 Y9.12 Z5.54 F1800.0 E393.936
G1 X8.8 Y-9.12 Z5.54 F1800.0 E394.827
G1 F798.0
G1 E394.327
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P58 (display progress)
(<layer> 5.805 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z5.805 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z5.805 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z5.805 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z5.805 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.38 Z5.8 F3000.0
G1 F798.0
G1 E394.627
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z5.8 F1800.0 E394.628
G1 X9.4 Y-9.4 Z5.8 F1800.0 E395.547
G1 X9.4 Y9.4 Z5.8 F1800.0 E396.465
G1 X-9.4 Y9.4 Z5.8 F1800.0 E397.383
G1 X-9.4 Y-9.38 Z5.8 F1800.0 E398.3
G1 F798.0
G1 E398.3
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.38 Z5.8 F3000.0
G1 F798.0
G1 E398.3
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z5.8 F900.0 E398.301
G1 X-9.8 Y-9.8 Z5.8 F900.0 E398.321
G1 X9.8 Y-9.8 Z5.8 F900.0 E399.278
G1 X9.8 Y9.8 Z5.8 F900.0 E400.235
G1 X-9.8 Y9.8 Z5.8 F900.0 E401.192
G1 X-9.8 Y-9.38 Z5.8 F900.0 E402.129
G1 F798.0
G1 E402.034
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z5.805 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z5.805 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z5.805 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z5.805 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z5.8 F3000.0
G1 F798.0
G1 E402.091
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z5.8 F1800.0 E402.286
G1 X9.12 Y-4.4 Z5.8 F1800.0 E403.177
G1 X9.12 Y-8.8 Z5.8 F1800.0 E403.392
G1 X-9.12 Y-8.8 Z5.8 F1800.0 E404.283
G1 F798.0
G1 E403.783
G1 F1800.0
M103
G1 X9.12 Y7.2 Z5.8 F3000.0
G1 F798.0
G1 E404.083
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z5.8 F1800.0 E404.63
G1 X5.86 Y-4.0 Z5.8 F1800.0 E404.789
G1 X2.14 Y-1.33 Z5.8 F1800.0 E405.013
G1 X1.86 Y-1.33 Z5.8 F1800.0 E405.026
G1 X-1.86 Y-4.0 Z5.8 F1800.0 E405.25
G1 X-2.14 Y-4.0 Z5.8 F1800.0 E405.264
G1 X-5.86 Y-1.33 Z5.8 F1800.0 E405.487
G1 X-6.14 Y-1.33 Z5.8 F1800.0 E405.501
G1 X-9.12 Y-4.0 Z5.8 F1800.0 E405.696
G1 X-9.12 Y7.2 Z5.8 F1800.0 E406.243
G1 F798.0
G1 E406.243
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z5.8 F3000.0
G1 F798.0
G1 E406.243
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z5.8 F1800.0 E406.263
G1 X-6.14 Y4.0 Z5.8 F1800.0 E406.491
G1 X2.14 Y4.0 Z5.8 F1800.0 E406.895
G1 X5.86 Y6.67 Z5.8 F1800.0 E407.119
G1 X6.14 Y6.67 Z5.8 F1800.0 E407.133
G1 X9.12 Y7.6 Z5.8 F1800.0 E407.285
G1 X9.12 Y8.8 Z5.8 F1800.0 E407.344
G1 X-1.86 Y6.67 Z5.8 F1800.0 E407.89
G1 X-2.14 Y6.67 Z5.8 F1800.0 E407.904
G1 X-9.12 Y8.4 Z5.8 F1800.0 E408.255
G1 X-9.12 Y8.8 Z5.8 F1800.0 E408.274
G1 F798.0
G1 E407.774
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P60 (display progress)
(<layer> 6.075 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z6.075 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z6.075 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z6.075 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z6.075 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.07 Z6.08 F3000.0
G1 F798.0
G1 E408.074
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z6.08 F1800.0 E408.09
G1 X9.4 Y-9.4 Z6.08 F1800.0 E409.009
G1 X9.4 Y9.4 Z6.08 F1800.0 E409.927
G1 X-9.4 Y9.4 Z6.08 F1800.0 E410.845
G1 X-9.4 Y-9.07 Z6.08 F1800.0 E411.747
G1 F798.0
G1 E411.747
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.07 Z6.08 F3000.0
G1 F798.0
G1 E411.747
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z6.08 F900.0 E411.763
G1 X-9.8 Y-9.8 Z6.08 F900.0 E411.783
G1 X9.8 Y-9.8 Z6.08 F900.0 E412.74
G1 X9.8 Y9.8 Z6.08 F900.0 E413.697
G1 X-9.8 Y9.8 Z6.08 F900.0 E414.654
G1 X-9.8 Y-9.07 Z6.08 F900.0 E415.576
G1 F798.0
G1 E415.076
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z6.075 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z6.075 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z6.075 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z6.075 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z6.08 F3000.0
G1 F798.0
G1 E415.376
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z6.08 F1800.0 E415.552
G1 X-2.13 Y-4.0 Z6.08 F1800.0 E415.81
G1 X-5.87 Y-1.33 Z6.08 F1800.0 E416.035
G1 X-5.87 Y4.0 Z6.08 F1800.0 E416.295
G1 X-2.13 Y6.67 Z6.08 F1800.0 E416.52
G1 X-0.8 Y9.12 Z6.08 F1800.0 E416.656
G1 X-4.4 Y9.12 Z6.08 F1800.0 E416.832
G1 F798.0
G1 E416.332
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z6.08 F3000.0
G1 F798.0
G1 E416.632
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z6.08 F1800.0 E416.808
G1 X-6.13 Y4.0 Z6.08 F1800.0 E417.066
G1 X-6.13 Y-1.33 Z6.08 F1800.0 E417.327
G1 X-4.8 Y-9.12 Z6.08 F1800.0 E417.713
G1 X-8.8 Y-9.12 Z6.08 F1800.0 E417.908
G1 X-8.8 Y9.12 Z6.08 F1800.0 E418.799
G1 F798.0
G1 E418.299
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z6.08 F3000.0
G1 F798.0
G1 E418.599
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z6.08 F1800.0 E418.794
G1 X-1.87 Y-4.0 Z6.08 F1800.0 E419.054
G1 X1.87 Y-1.33 Z6.08 F1800.0 E419.279
G1 X1.87 Y4.0 Z6.08 F1800.0 E419.539
G1 X-1.87 Y6.67 Z6.08 F1800.0 E419.764
G1 X-0.4 Y9.12 Z6.08 F1800.0 E419.904
G1 X7.2 Y9.12 Z6.08 F1800.0 E420.275
G1 X5.87 Y6.67 Z6.08 F1800.0 E420.411
G1 X2.13 Y4.0 Z6.08 F1800.0 E420.636
G1 X2.13 Y-1.33 Z6.08 F1800.0 E420.896
G1 X5.87 Y-4.0 Z6.08 F1800.0 E421.121
G1 X7.2 Y-9.12 Z6.08 F1800.0 E421.379
G1 X4.0 Y-9.12 Z6.08 F1800.0 E421.536
G1 F798.0
G1 E421.036
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z6.08 F3000.0
G1 F798.0
G1 E421.336
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z6.08 F1800.0 E421.375
G1 X6.13 Y-4.0 Z6.08 F1800.0 E421.635
G1 X6.13 Y6.67 Z6.08 F1800.0 E422.156
G1 X7.6 Y9.12 Z6.08 F1800.0 E422.296
G1 X8.8 Y9.12 Z6.08 F1800.0 E422.354
G1 X8.8 Y-9.12 Z6.08 F1800.0 E423.245
G1 F798.0
G1 E422.745
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P62 (display progress)
(<layer> 6.345 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z6.345 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z6.345 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z6.345 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z6.345 </boundaryPoint>)
(<loop> outer )
G1 X-9.23 Y-9.4 Z6.34 F3000.0
G1 F798.0
G1 E423.045
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z6.34 F1800.0 E423.955
G1 X9.4 Y9.4 Z6.34 F1800.0 E424.873
G1 X-9.4 Y9.4 Z6.34 F1800.0 E425.791
G1 X-9.4 Y-9.4 Z6.34 F1800.0 E426.71
G1 X-9.23 Y-9.4 Z6.34 F1800.0 E426.718
G1 F798.0
G1 E426.718
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.57 Z6.34 F3000.0
G1 F798.0
G1 E426.718
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z6.34 F900.0 E426.729
G1 X9.8 Y-9.8 Z6.34 F900.0 E427.686
G1 X9.8 Y9.8 Z6.34 F900.0 E428.644
G1 X-9.8 Y9.8 Z6.34 F900.0 E429.601
G1 X-9.8 Y-9.4 Z6.34 F900.0 E430.539
G1 X-9.8 Y-9.57 Z6.34 F900.0 E430.547
G1 F798.0
G1 E430.372
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z6.345 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z6.345 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z6.345 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z6.345 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z6.34 F3000.0
G1 F798.0
G1 E430.477
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z6.34 F1800.0 E430.672
G1 X9.12 Y-4.4 Z6.34 F1800.0 E431.563
G1 X9.12 Y-8.8 Z6.34 F1800.0 E431.778
G1 X-9.12 Y-8.8 Z6.34 F1800.0 E432.669
G1 F798.0
G1 E432.169
G1 F1800.0
M103
G1 X9.12 Y7.2 Z6.34 F3000.0
G1 F798.0
G1 E432.469
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z6.34 F1800.0 E433.016
G1 X5.86 Y-4.0 Z6.34 F1800.0 E433.175
G1 X2.14 Y-1.33 Z6.34 F1800.0 E433.399
G1 X1.86 Y-1.33 Z6.34 F1800.0 E433.412
G1 X-1.86 Y-4.0 Z6.34 F1800.0 E433.636
G1 X-2.14 Y-4.0 Z6.34 F1800.0 E433.649
G1 X-5.86 Y-1.33 Z6.34 F1800.0 E433.873
G1 X-6.14 Y-1.33 Z6.34 F1800.0 E433.887
G1 X-9.12 Y-4.0 Z6.34 F1800.0 E434.082
G1 X-9.12 Y7.2 Z6.34 F1800.0 E434.629
G1 F798.0
G1 E434.629
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z6.34 F3000.0
G1 F798.0
G1 E434.629
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z6.34 F1800.0 E434.649
G1 X-6.14 Y4.0 Z6.34 F1800.0 E434.877
G1 X2.14 Y4.0 Z6.34 F1800.0 E435.281
G1 X5.86 Y6.67 Z6.34 F1800.0 E435.505
G1 X6.14 Y6.67 Z6.34 F1800.0 E435.518
G1 X9.12 Y7.6 Z6.34 F1800.0 E435.671
G1 X9.12 Y8.8 Z6.34 F1800.0 E435.73
G1 X-1.86 Y6.67 Z6.34 F1800.0 E436.276
G1 X-2.14 Y6.67 Z6.34 F1800.0 E436.289
G1 X-9.12 Y8.4 Z6.34 F1800.0 E436.641
G1 X-9.12 Y8.8 Z6.34 F1800.0 E436.66
G1 F798.0
G1 E436.16
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P65 (display progress)
(<layer> 6.615 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z6.615 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z6.615 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z6.615 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z6.615 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.26 Z6.62 F3000.0
G1 F798.0
G1 E436.46
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z6.62 F1800.0 E436.467
G1 X9.4 Y-9.4 Z6.62 F1800.0 E437.385
G1 X9.4 Y9.4 Z6.62 F1800.0 E438.303
G1 X-9.4 Y9.4 Z6.62 F1800.0 E439.222
G1 X-9.4 Y-9.26 Z6.62 F1800.0 E440.133
G1 F798.0
G1 E440.133
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.26 Z6.62 F3000.0
G1 F798.0
G1 E440.133
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z6.62 F900.0 E440.14
G1 X-9.8 Y-9.8 Z6.62 F900.0 E440.159
G1 X9.8 Y-9.8 Z6.62 F900.0 E441.117
G1 X9.8 Y9.8 Z6.62 F900.0 E442.074
G1 X-9.8 Y9.8 Z6.62 F900.0 E443.031
G1 X-9.8 Y-9.26 Z6.62 F900.0 E443.962
G1 F798.0
G1 E443.462
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z6.615 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z6.615 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z6.615 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z6.615 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z6.62 F3000.0
G1 F798.0
G1 E443.762
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z6.62 F1800.0 E443.938
G1 X-2.13 Y-4.0 Z6.62 F1800.0 E444.196
G1 X-5.87 Y-1.33 Z6.62 F1800.0 E444.421
G1 X-5.87 Y4.0 Z6.62 F1800.0 E444.681
G1 X-2.13 Y6.67 Z6.62 F1800.0 E444.906
G1 X-0.8 Y9.12 Z6.62 F1800.0 E445.042
G1 X-4.4 Y9.12 Z6.62 F1800.0 E445.218
G1 F798.0
G1 E444.718
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z6.62 F3000.0
G1 F798.0
G1 E445.018
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z6.62 F1800.0 E445.194
G1 X-6.13 Y4.0 Z6.62 F1800.0 E445.452
G1 X-6.13 Y-1.33 Z6.62 F1800.0 E445.713
G1 X-4.8 Y-9.12 Z6.62 F1800.0 E446.098
G1 X-8.8 Y-9.12 Z6.62 F1800.0 E446.294
G1 X-8.8 Y9.12 Z6.62 F1800.0 E447.185
G1 F798.0
G1 E446.685
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z6.62 F3000.0
G1 F798.0
G1 E446.985
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z6.62 F1800.0 E447.18
G1 X-1.87 Y-4.0 Z6.62 F1800.0 E447.44
G1 X1.87 Y-1.33 Z6.62 F1800.0 E447.665
G1 X1.87 Y4.0 Z6.62 F1800.0 E447.925
G1 X-1.87 Y6.67 Z6.62 F1800.0 E448.15
G1 X-0.4 Y9.12 Z6.62 F1800.0 E448.29
G1 X7.2 Y9.12 Z6.62 F1800.0 E448.661
G1 X5.87 Y6.67 Z6.62 F1800.0 E448.797
G1 X2.13 Y4.0 Z6.62 F1800.0 E449.022
G1 X2.13 Y-1.33 Z6.62 F1800.0 E449.282
G1 X5.87 Y-4.0 Z6.62 F1800.0 E449.507
G1 X7.2 Y-9.12 Z6.62 F1800.0 E449.765
G1 X4.0 Y-9.12 Z6.62 F1800.0 E449.921
G1 F798.0
G1 E449.421
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z6.62 F3000.0
G1 F798.0
G1 E449.721
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z6.62 F1800.0 E449.76
G1 X6.13 Y-4.0 Z6.62 F1800.0 E450.021
G1 X6.13 Y6.67 Z6.62 F1800.0 E450.542
G1 X7.6 Y9.12 Z6.62 F1800.0 E450.681
G1 X8.8 Y9.12 Z6.62 F1800.0 E450.74
G1 X8.8 Y-9.12 Z6.62 F1800.0 E451.631
G1 F798.0
G1 E451.131
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P67 (display progress)
(<layer> 6.885 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z6.885 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z6.885 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z6.885 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z6.885 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-8.96 Z6.88 F3000.0
G1 F798.0
G1 E451.431
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z6.88 F1800.0 E451.453
G1 X9.4 Y-9.4 Z6.88 F1800.0 E452.371
G1 X9.4 Y9.4 Z6.88 F1800.0 E453.289
G1 X-9.4 Y9.4 Z6.88 F1800.0 E454.207
G1 X-9.4 Y-8.96 Z6.88 F1800.0 E455.104
G1 F798.0
G1 E455.104
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-8.96 Z6.88 F3000.0
G1 F798.0
G1 E455.104
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z6.88 F900.0 E455.125
G1 X-9.8 Y-9.8 Z6.88 F900.0 E455.145
G1 X9.8 Y-9.8 Z6.88 F900.0 E456.102
G1 X9.8 Y9.8 Z6.88 F900.0 E457.059
G1 X-9.8 Y9.8 Z6.88 F900.0 E458.017
G1 X-9.8 Y-8.96 Z6.88 F900.0 E458.933
G1 F798.0
G1 E458.933
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z6.885 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z6.885 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z6.885 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z6.885 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z6.88 F3000.0
G1 F798.0
G1 E458.933
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z6.88 F1800.0 E459.128
G1 X9.12 Y-4.4 Z6.88 F1800.0 E460.019
G1 X9.12 Y-8.8 Z6.88 F1800.0 E460.234
G1 X-9.12 Y-8.8 Z6.88 F1800.0 E461.125
G1 F798.0
G1 E460.625
G1 F1800.0
M103
G1 X9.12 Y7.2 Z6.88 F3000.0
G1 F798.0
G1 E460.925
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z6.88 F1800.0 E461.472
G1 X5.86 Y-4.0 Z6.88 F1800.0 E461.631
G1 X2.14 Y-1.33 Z6.88 F1800.0 E461.854
G1 X1.86 Y-1.33 Z6.88 F1800.0 E461.868
G1 X-1.86 Y-4.0 Z6.88 F1800.0 E462.092
G1 X-2.14 Y-4.0 Z6.88 F1800.0 E462.105
G1 X-5.86 Y-1.33 Z6.88 F1800.0 E462.329
G1 X-6.14 Y-1.33 Z6.88 F1800.0 E462.342
G1 X-9.12 Y-4.0 Z6.88 F1800.0 E462.538
G1 X-9.12 Y7.2 Z6.88 F1800.0 E463.085
G1 F798.0
G1 E463.085
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z6.88 F3000.0
G1 F798.0
G1 E463.085
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z6.88 F1800.0 E463.104
G1 X-6.14 Y4.0 Z6.88 F1800.0 E463.333
G1 X2.14 Y4.0 Z6.88 F1800.0 E463.737
G1 X5.86 Y6.67 Z6.88 F1800.0 E463.961
G1 X6.14 Y6.67 Z6.88 F1800.0 E463.974
G1 X9.12 Y7.6 Z6.88 F1800.0 E464.127
G1 X9.12 Y8.8 Z6.88 F1800.0 E464.185
G1 X-1.86 Y6.67 Z6.88 F1800.0 E464.732
G1 X-2.14 Y6.67 Z6.88 F1800.0 E464.745
G1 X-9.12 Y8.4 Z6.88 F1800.0 E465.097
G1 X-9.12 Y8.8 Z6.88 F1800.0 E465.116
G1 F798.0
G1 E464.616
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P70 (display progress)
(<layer> 7.155 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z7.155 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z7.155 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z7.155 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z7.155 </boundaryPoint>)
(<loop> outer )
G1 X-9.35 Y-9.4 Z7.16 F3000.0
G1 F798.0
G1 E464.916
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z7.16 F1800.0 E465.832
G1 X9.4 Y9.4 Z7.16 F1800.0 E466.75
G1 X-9.4 Y9.4 Z7.16 F1800.0 E467.668
G1 X-9.4 Y-9.4 Z7.16 F1800.0 E468.586
G1 X-9.35 Y-9.4 Z7.16 F1800.0 E468.589
G1 F798.0
G1 E468.589
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.45 Z7.16 F3000.0
G1 F798.0
G1 E468.589
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z7.16 F900.0 E468.606
G1 X9.8 Y-9.8 Z7.16 F900.0 E469.563
G1 X9.8 Y9.8 Z7.16 F900.0 E470.52
G1 X-9.8 Y9.8 Z7.16 F900.0 E471.478
G1 X-9.8 Y-9.4 Z7.16 F900.0 E472.415
G1 X-9.8 Y-9.45 Z7.16 F900.0 E472.418
G1 F798.0
G1 E471.918
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z7.155 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z7.155 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z7.155 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z7.155 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z7.16 F3000.0
G1 F798.0
G1 E472.218
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z7.16 F1800.0 E472.394
G1 X-2.13 Y-4.0 Z7.16 F1800.0 E472.652
G1 X-5.87 Y-1.33 Z7.16 F1800.0 E472.877
G1 X-5.87 Y4.0 Z7.16 F1800.0 E473.137
G1 X-2.13 Y6.67 Z7.16 F1800.0 E473.362
G1 X-0.8 Y9.12 Z7.16 F1800.0 E473.498
G1 X-4.4 Y9.12 Z7.16 F1800.0 E473.674
G1 F798.0
G1 E473.174
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z7.16 F3000.0
G1 F798.0
G1 E473.474
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z7.16 F1800.0 E473.65
G1 X-6.13 Y4.0 Z7.16 F1800.0 E473.908
G1 X-6.13 Y-1.33 Z7.16 F1800.0 E474.168
G1 X-4.8 Y-9.12 Z7.16 F1800.0 E474.554
G1 X-8.8 Y-9.12 Z7.16 F1800.0 E474.749
G1 X-8.8 Y9.12 Z7.16 F1800.0 E475.64
G1 F798.0
G1 E475.14
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z7.16 F3000.0
G1 F798.0
G1 E475.44
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z7.16 F1800.0 E475.636
G1 X-1.87 Y-4.0 Z7.16 F1800.0 E475.896
G1 X1.87 Y-1.33 Z7.16 F1800.0 E476.121
G1 X1.87 Y4.0 Z7.16 F1800.0 E476.381
G1 X-1.87 Y6.67 Z7.16 F1800.0 E476.606
G1 X-0.4 Y9.12 Z7.16 F1800.0 E476.745
G1 X7.2 Y9.12 Z7.16 F1800.0 E477.117
G1 X5.87 Y6.67 Z7.16 F1800.0 E477.253
G1 X2.13 Y4.0 Z7.16 F1800.0 E477.477
G1 X2.13 Y-1.33 Z7.16 F1800.0 E477.738
G1 X5.87 Y-4.0 Z7.16 F1800.0 E477.963
G1 X7.2 Y-9.12 Z7.16 F1800.0 E478.221
G1 X4.0 Y-9.12 Z7.16 F1800.0 E478.377
G1 F798.0
G1 E477.877
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z7.16 F3000.0
G1 F798.0
G1 E478.177
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z7.16 F1800.0 E478.216
G1 X6.13 Y-4.0 Z7.16 F1800.0 E478.476
G1 X6.13 Y6.67 Z7.16 F1800.0 E478.997
G1 X7.6 Y9.12 Z7.16 F1800.0 E479.137
G1 X8.8 Y9.12 Z7.16 F1800.0 E479.196
G1 X8.8 Y-9.12 Z7.16 F1800.0 E480.087
G1 F798.0
G1 E479.587
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P72 (display progress)
(<layer> 7.425 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z7.425 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z7.425 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z7.425 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z7.425 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.14 Z7.42 F3000.0
G1 F798.0
G1 E479.887
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z7.42 F1800.0 E479.899
G1 X9.4 Y-9.4 Z7.42 F1800.0 E480.817
G1 X9.4 Y9.4 Z7.42 F1800.0 E481.736
G1 X-9.4 Y9.4 Z7.42 F1800.0 E482.654
G1 X-9.4 Y-9.14 Z7.42 F1800.0 E483.559
G1 F798.0
G1 E483.559
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.14 Z7.42 F3000.0
G1 F798.0
G1 E483.559
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z7.42 F900.0 E483.572
G1 X-9.8 Y-9.8 Z7.42 F900.0 E483.591
G1 X9.8 Y-9.8 Z7.42 F900.0 E484.549
G1 X9.8 Y9.8 Z7.42 F900.0 E485.506
G1 X-9.8 Y9.8 Z7.42 F900.0 E486.463
G1 X-9.8 Y-9.14 Z7.42 F900.0 E487.388
G1 F798.0
G1 E487.384
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z7.425 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z7.425 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z7.425 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z7.425 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z7.42 F3000.0
G1 F798.0
G1 E487.387
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z7.42 F1800.0 E487.582
G1 X9.12 Y-4.4 Z7.42 F1800.0 E488.473
G1 X9.12 Y-8.8 Z7.42 F1800.0 E488.688
G1 X-9.12 Y-8.8 Z7.42 F1800.0 E489.579
G1 F798.0
G1 E489.079
G1 F1800.0
M103
G1 X9.12 Y7.2 Z7.42 F3000.0
G1 F798.0
G1 E489.379
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z7.42 F1800.0 E489.926
G1 X5.86 Y-4.0 Z7.42 F1800.0 E490.085
G1 X2.14 Y-1.33 Z7.42 F1800.0 E490.309
G1 X1.86 Y-1.33 Z7.42 F1800.0 E490.322
G1 X-1.86 Y-4.0 Z7.42 F1800.0 E490.546
G1 X-2.14 Y-4.0 Z7.42 F1800.0 E490.559
G1 X-5.86 Y-1.33 Z7.42 F1800.0 E490.783
G1 X-6.14 Y-1.33 Z7.42 F1800.0 E490.797
G1 X-9.12 Y-4.0 Z7.42 F1800.0 E490.992
G1 X-9.12 Y7.2 Z7.42 F1800.0 E491.539
G1 F798.0
G1 E491.539
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z7.42 F3000.0
G1 F798.0
G1 E491.539
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z7.42 F1800.0 E491.559
G1 X-6.14 Y4.0 Z7.42 F1800.0 E491.787
G1 X2.14 Y4.0 Z7.42 F1800.0 E492.191
G1 X5.86 Y6.67 Z7.42 F1800.0 E492.415
G1 X6.14 Y6.67 Z7.42 F1800.0 E492.428
G1 X9.12 Y7.6 Z7.42 F1800.0 E492.581
G1 X9.12 Y8.8 Z7.42 F1800.0 E492.64
G1 X-1.86 Y6.67 Z7.42 F1800.0 E493.186
G1 X-2.14 Y6.67 Z7.42 F1800.0 E493.199
G1 X-9.12 Y8.4 Z7.42 F1800.0 E493.551
G1 X-9.12 Y8.8 Z7.42 F1800.0 E493.57
G1 F798.0
G1 E493.07
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P74 (display progress)
(<layer> 7.695 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z7.695 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z7.695 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z7.695 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z7.695 </boundaryPoint>)
(<loop> outer )
G1 X-9.16 Y-9.4 Z7.7 F3000.0
G1 F798.0
G1 E493.37
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z7.7 F1800.0 E494.277
G1 X9.4 Y9.4 Z7.7 F1800.0 E495.195
G1 X-9.4 Y9.4 Z7.7 F1800.0 E496.113
G1 X-9.4 Y-9.4 Z7.7 F1800.0 E497.031
G1 X-9.16 Y-9.4 Z7.7 F1800.0 E497.043
G1 F798.0
G1 E497.043
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.64 Z7.7 F3000.0
G1 F798.0
G1 E497.043
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z7.7 F900.0 E497.051
G1 X9.8 Y-9.8 Z7.7 F900.0 E498.008
G1 X9.8 Y9.8 Z7.7 F900.0 E498.965
G1 X-9.8 Y9.8 Z7.7 F900.0 E499.923
G1 X-9.8 Y-9.4 Z7.7 F900.0 E500.86
G1 X-9.8 Y-9.64 Z7.7 F900.0 E500.872
G1 F798.0
G1 E500.372
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z7.695 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z7.695 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z7.695 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z7.695 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z7.7 F3000.0
G1 F798.0
G1 E500.672
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z7.7 F1800.0 E500.848
G1 X-2.13 Y-4.0 Z7.7 F1800.0 E501.106
G1 X-5.87 Y-1.33 Z7.7 F1800.0 E501.331
G1 X-5.87 Y4.0 Z7.7 F1800.0 E501.591
G1 X-2.13 Y6.67 Z7.7 F1800.0 E501.816
G1 X-0.8 Y9.12 Z7.7 F1800.0 E501.952
G1 X-4.4 Y9.12 Z7.7 F1800.0 E502.128
G1 F798.0
G1 E501.628
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z7.7 F3000.0
G1 F798.0
G1 E501.928
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z7.7 F1800.0 E502.104
G1 X-6.13 Y4.0 Z7.7 F1800.0 E502.362
G1 X-6.13 Y-1.33 Z7.7 F1800.0 E502.623
G1 X-4.8 Y-9.12 Z7.7 F1800.0 E503.008
G1 X-8.8 Y-9.12 Z7.7 F1800.0 E503.204
G1 X-8.8 Y9.12 Z7.7 F1800.0 E504.095
G1 F798.0
G1 E503.595
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z7.7 F3000.0
G1 F798.0
G1 E503.895
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z7.7 F1800.0 E504.09
G1 X-1.87 Y-4.0 Z7.7 F1800.0 E504.35
G1 X1.87 Y-1.33 Z7.7 F1800.0 E504.575
G1 X1.87 Y4.0 Z7.7 F1800.0 E504.835
G1 X-1.87 Y6.67 Z7.7 F1800.0 E505.06
G1 X-0.4 Y9.12 Z7.7 F1800.0 E505.2
G1 X7.2 Y9.12 Z7.7 F1800.0 E505.571
G1 X5.87 Y6.67 Z7.7 F1800.0 E505.707
G1 X2.13 Y4.0 Z7.7 F1800.0 E505.932
G1 X2.13 Y-1.33 Z7.7 F1800.0 E506.192
G1 X5.87 Y-4.0 Z7.7 F1800.0 E506.417
G1 X7.2 Y-9.12 Z7.7 F1800.0 E506.675
G1 X4.0 Y-9.12 Z7.7 F1800.0 E506.831
G1 F798.0
G1 E506.331
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z7.7 F3000.0
G1 F798.0
G1 E506.631
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z7.7 F1800.0 E506.67
G1 X6.13 Y-4.0 Z7.7 F1800.0 E506.931
G1 X6.13 Y6.67 Z7.7 F1800.0 E507.452
G1 X7.6 Y9.12 Z7.7 F1800.0 E507.591
G1 X8.8 Y9.12 Z7.7 F1800.0 E507.65
G1 X8.8 Y-9.12 Z7.7 F1800.0 E508.541
G1 F798.0
G1 E508.041
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P77 (display progress)
(<layer> 7.965 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z7.965 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z7.965 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z7.965 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z7.965 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.33 Z7.96 F3000.0
G1 F798.0
G1 E508.341
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z7.96 F1800.0 E508.344
G1 X9.4 Y-9.4 Z7.96 F1800.0 E509.262
G1 X9.4 Y9.4 Z7.96 F1800.0 E510.181
G1 X-9.4 Y9.4 Z7.96 F1800.0 E511.099
G1 X-9.4 Y-9.33 Z7.96 F1800.0 E512.014
G1 F798.0
G1 E512.014
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.33 Z7.96 F3000.0
G1 F798.0
G1 E512.014
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z7.96 F900.0 E512.017
G1 X-9.8 Y-9.8 Z7.96 F900.0 E512.036
G1 X9.8 Y-9.8 Z7.96 F900.0 E512.994
G1 X9.8 Y9.8 Z7.96 F900.0 E513.951
G1 X-9.8 Y9.8 Z7.96 F900.0 E514.908
G1 X-9.8 Y-9.33 Z7.96 F900.0 E515.843
G1 F798.0
G1 E515.765
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z7.965 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z7.965 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z7.965 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z7.965 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z7.96 F3000.0
G1 F798.0
G1 E515.812
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z7.96 F1800.0 E516.007
G1 X9.12 Y-4.4 Z7.96 F1800.0 E516.898
G1 X9.12 Y-8.8 Z7.96 F1800.0 E517.113
G1 X-9.12 Y-8.8 Z7.96 F1800.0 E518.004
G1 F798.0
G1 E517.504
G1 F1800.0
M103
G1 X9.12 Y7.2 Z7.96 F3000.0
G1 F798.0
G1 E517.804
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z7.96 F1800.0 E518.351
G1 X5.86 Y-4.0 Z7.96 F1800.0 E518.51
G1 X2.14 Y-1.33 Z7.96 F1800.0 E518.733
G1 X1.86 Y-1.33 Z7.96 F1800.0 E518.747
G1 X-1.86 Y-4.0 Z7.96 F1800.0 E518.971
G1 X-2.14 Y-4.0 Z7.96 F1800.0 E518.984
G1 X-5.86 Y-1.33 Z7.96 F1800.0 E519.208
G1 X-6.14 Y-1.33 Z7.96 F1800.0 E519.222
G1 X-9.12 Y-4.0 Z7.96 F1800.0 E519.417
G1 X-9.12 Y7.2 Z7.96 F1800.0 E519.964
G1 F798.0
G1 E519.964
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z7.96 F3000.0
G1 F798.0
G1 E519.964
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z7.96 F1800.0 E519.983
G1 X-6.14 Y4.0 Z7.96 F1800.0 E520.212
G1 X2.14 Y4.0 Z7.96 F1800.0 E520.616
G1 X5.86 Y6.67 Z7.96 F1800.0 E520.84
G1 X6.14 Y6.67 Z7.96 F1800.0 E520.853
G1 X9.12 Y7.6 Z7.96 F1800.0 E521.006
G1 X9.12 Y8.8 Z7.96 F1800.0 E521.064
G1 X-1.86 Y6.67 Z7.96 F1800.0 E521.611
G1 X-2.14 Y6.67 Z7.96 F1800.0 E521.624
G1 X-9.12 Y8.4 Z7.96 F1800.0 E521.976
G1 X-9.12 Y8.8 Z7.96 F1800.0 E521.995
G1 F798.0
G1 E521.495
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P79 (display progress)
(<layer> 8.235 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z8.235 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z8.235 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z8.235 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z8.235 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.03 Z8.23 F3000.0
G1 F798.0
G1 E521.795
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z8.23 F1800.0 E521.813
G1 X9.4 Y-9.4 Z8.23 F1800.0 E522.732
G1 X9.4 Y9.4 Z8.23 F1800.0 E523.65
G1 X-9.4 Y9.4 Z8.23 F1800.0 E524.568
G1 X-9.4 Y-9.03 Z8.23 F1800.0 E525.468
G1 F798.0
G1 E525.468
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.03 Z8.23 F3000.0
G1 F798.0
G1 E525.468
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z8.23 F900.0 E525.486
G1 X-9.8 Y-9.8 Z8.23 F900.0 E525.506
G1 X9.8 Y-9.8 Z8.23 F900.0 E526.463
G1 X9.8 Y9.8 Z8.23 F900.0 E527.42
G1 X-9.8 Y9.8 Z8.23 F900.0 E528.377
G1 X-9.8 Y-9.03 Z8.23 F900.0 E529.297
G1 F798.0
G1 E528.797
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z8.235 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z8.235 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z8.235 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z8.235 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z8.23 F3000.0
G1 F798.0
G1 E529.097
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z8.23 F1800.0 E529.273
G1 X-2.13 Y-4.0 Z8.23 F1800.0 E529.531
G1 X-5.87 Y-1.33 Z8.23 F1800.0 E529.756
G1 X-5.87 Y4.0 Z8.23 F1800.0 E530.016
G1 X-2.13 Y6.67 Z8.23 F1800.0 E530.241
G1 X-0.8 Y9.12 Z8.23 F1800.0 E530.377
G1 X-4.4 Y9.12 Z8.23 F1800.0 E530.553
G1 F798.0
G1 E530.053
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z8.23 F3000.0
G1 F798.0
G1 E530.353
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z8.23 F1800.0 E530.529
G1 X-6.13 Y4.0 Z8.23 F1800.0 E530.787
G1 X-6.13 Y-1.33 Z8.23 F1800.0 E531.047
G1 X-4.8 Y-9.12 Z8.23 F1800.0 E531.433
G1 X-8.8 Y-9.12 Z8.23 F1800.0 E531.629
G1 X-8.8 Y9.12 Z8.23 F1800.0 E532.519
G1 F798.0
G1 E532.019
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z8.23 F3000.0
G1 F798.0
G1 E532.319
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z8.23 F1800.0 E532.515
G1 X-1.87 Y-4.0 Z8.23 F1800.0 E532.775
G1 X1.87 Y-1.33 Z8.23 F1800.0 E533.0
G1 X1.87 Y4.0 Z8.23 F1800.0 E533.26
G1 X-1.87 Y6.67 Z8.23 F1800.0 E533.485
G1 X-0.4 Y9.12 Z8.23 F1800.0 E533.625
G1 X7.2 Y9.12 Z8.23 F1800.0 E533.996
G1 X5.87 Y6.67 Z8.23 F1800.0 E534.132
G1 X2.13 Y4.0 Z8.23 F1800.0 E534.357
G1 X2.13 Y-1.33 Z8.23 F1800.0 E534.617
G1 X5.87 Y-4.0 Z8.23 F1800.0 E534.842
G1 X7.2 Y-9.12 Z8.23 F1800.0 E535.1
G1 X4.0 Y-9.12 Z8.23 F1800.0 E535.256
G1 F798.0
G1 E534.756
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z8.23 F3000.0
G1 F798.0
G1 E535.056
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z8.23 F1800.0 E535.095
G1 X6.13 Y-4.0 Z8.23 F1800.0 E535.356
G1 X6.13 Y6.67 Z8.23 F1800.0 E535.877
G1 X7.6 Y9.12 Z8.23 F1800.0 E536.016
G1 X8.8 Y9.12 Z8.23 F1800.0 E536.075
G1 X8.8 Y-9.12 Z8.23 F1800.0 E536.966
G1 F798.0
G1 E536.466
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P82 (display progress)
(<layer> 8.505 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z8.505 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z8.505 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z8.505 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z8.505 </boundaryPoint>)
(<loop> outer )
G1 X-9.28 Y-9.4 Z8.51 F3000.0
G1 F798.0
G1 E536.766
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z8.51 F1800.0 E537.678
G1 X9.4 Y9.4 Z8.51 F1800.0 E538.596
G1 X-9.4 Y9.4 Z8.51 F1800.0 E539.514
G1 X-9.4 Y-9.4 Z8.51 F1800.0 E540.433
G1 X-9.28 Y-9.4 Z8.51 F1800.0 E540.439
G1 F798.0
G1 E540.439
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.52 Z8.51 F3000.0
G1 F798.0
G1 E540.439
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z8.51 F900.0 E540.452
G1 X9.8 Y-9.8 Z8.51 F900.0 E541.409
G1 X9.8 Y9.8 Z8.51 F900.0 E542.367
G1 X-9.8 Y9.8 Z8.51 F900.0 E543.324
G1 X-9.8 Y-9.4 Z8.51 F900.0 E544.262
G1 X-9.8 Y-9.52 Z8.51 F900.0 E544.268
G1 F798.0
G1 E544.112
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z8.505 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z8.505 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z8.505 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z8.505 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z8.51 F3000.0
G1 F798.0
G1 E544.205
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z8.51 F1800.0 E544.401
G1 X9.12 Y-4.4 Z8.51 F1800.0 E545.291
G1 X9.12 Y-8.8 Z8.51 F1800.0 E545.506
G1 X-9.12 Y-8.8 Z8.51 F1800.0 E546.397
G1 F798.0
G1 E545.897
G1 F1800.0
M103
G1 X9.12 Y7.2 Z8.51 F3000.0
G1 F798.0
G1 E546.197
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z8.51 F1800.0 E546.744
G1 X5.86 Y-4.0 Z8.51 F1800.0 E546.903
G1 X2.14 Y-1.33 Z8.51 F1800.0 E547.127
G1 X1.86 Y-1.33 Z8.51 F1800.0 E547.141
G1 X-1.86 Y-4.0 Z8.51 F1800.0 E547.364
G1 X-2.14 Y-4.0 Z8.51 F1800.0 E547.378
G1 X-5.86 Y-1.33 Z8.51 F1800.0 E547.601
G1 X-6.14 Y-1.33 Z8.51 F1800.0 E547.615
G1 X-9.12 Y-4.0 Z8.51 F1800.0 E547.81
G1 X-9.12 Y7.2 Z8.51 F1800.0 E548.357
G1 F798.0
G1 E548.357
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z8.51 F3000.0
G1 F798.0
G1 E548.357
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z8.51 F1800.0 E548.377
G1 X-6.14 Y4.0 Z8.51 F1800.0 E548.605
G1 X2.14 Y4.0 Z8.51 F1800.0 E549.009
G1 X5.86 Y6.67 Z8.51 F1800.0 E549.233
G1 X6.14 Y6.67 Z8.51 F1800.0 E549.247
G1 X9.12 Y7.6 Z8.51 F1800.0 E549.399
G1 X9.12 Y8.8 Z8.51 F1800.0 E549.458
G1 X-1.86 Y6.67 Z8.51 F1800.0 E550.004
G1 X-2.14 Y6.67 Z8.51 F1800.0 E550.018
G1 X-9.12 Y8.4 Z8.51 F1800.0 E550.369
G1 X-9.12 Y8.8 Z8.51 F1800.0 E550.389
G1 F798.0
G1 E549.889
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P84 (display progress)
(<layer> 8.775 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z8.775 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z8.775 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z8.775 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z8.775 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.22 Z8.78 F3000.0
G1 F798.0
G1 E550.189
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z8.78 F1800.0 E550.198
G1 X9.4 Y-9.4 Z8.78 F1800.0 E551.116
G1 X9.4 Y9.4 Z8.78 F1800.0 E552.034
G1 X-9.4 Y9.4 Z8.78 F1800.0 E552.952
G1 X-9.4 Y-9.22 Z8.78 F1800.0 E553.861
G1 F798.0
G1 E553.861
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.22 Z8.78 F3000.0
G1 F798.0
G1 E553.861
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z8.78 F900.0 E553.87
G1 X-9.8 Y-9.8 Z8.78 F900.0 E553.89
G1 X9.8 Y-9.8 Z8.78 F900.0 E554.847
G1 X9.8 Y9.8 Z8.78 F900.0 E555.804
G1 X-9.8 Y9.8 Z8.78 F900.0 E556.762
G1 X-9.8 Y-9.22 Z8.78 F900.0 E557.69
G1 F798.0
G1 E557.19
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z8.775 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z8.775 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z8.775 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z8.775 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-4.4 Y-9.12 Z8.78 F3000.0
G1 F798.0
G1 E557.49
G1 F3000.0
M101
G1 X-0.8 Y-9.12 Z8.78 F1800.0 E557.666
G1 X-2.13 Y-4.0 Z8.78 F1800.0 E557.924
G1 X-5.87 Y-1.33 Z8.78 F1800.0 E558.149
G1 X-5.87 Y4.0 Z8.78 F1800.0 E558.41
G1 X-2.13 Y6.67 Z8.78 F1800.0 E558.634
G1 X-0.8 Y9.12 Z8.78 F1800.0 E558.77
G1 X-4.4 Y9.12 Z8.78 F1800.0 E558.946
G1 F798.0
G1 E558.446
G1 F1800.0
M103
G1 X-8.4 Y9.12 Z8.78 F3000.0
G1 F798.0
G1 E558.746
G1 F3000.0
M101
G1 X-4.8 Y9.12 Z8.78 F1800.0 E558.922
G1 X-6.13 Y4.0 Z8.78 F1800.0 E559.18
G1 X-6.13 Y-1.33 Z8.78 F1800.0 E559.441
G1 X-4.8 Y-9.12 Z8.78 F1800.0 E559.827
G1 X-8.8 Y-9.12 Z8.78 F1800.0 E560.022
G1 X-8.8 Y9.12 Z8.78 F1800.0 E560.913
G1 F798.0
G1 E560.413
G1 F1800.0
M103
G1 X3.6 Y-9.12 Z8.78 F3000.0
G1 F798.0
G1 E560.713
G1 F3000.0
M101
G1 X-0.4 Y-9.12 Z8.78 F1800.0 E560.908
G1 X-1.87 Y-4.0 Z8.78 F1800.0 E561.168
G1 X1.87 Y-1.33 Z8.78 F1800.0 E561.393
G1 X1.87 Y4.0 Z8.78 F1800.0 E561.654
G1 X-1.87 Y6.67 Z8.78 F1800.0 E561.878
G1 X-0.4 Y9.12 Z8.78 F1800.0 E562.018
G1 X7.2 Y9.12 Z8.78 F1800.0 E562.389
G1 X5.87 Y6.67 Z8.78 F1800.0 E562.525
G1 X2.13 Y4.0 Z8.78 F1800.0 E562.75
G1 X2.13 Y-1.33 Z8.78 F1800.0 E563.01
G1 X5.87 Y-4.0 Z8.78 F1800.0 E563.235
G1 X7.2 Y-9.12 Z8.78 F1800.0 E563.493
G1 X4.0 Y-9.12 Z8.78 F1800.0 E563.65
G1 F798.0
G1 E563.15
G1 F1800.0
M103
G1 X8.4 Y-9.12 Z8.78 F3000.0
G1 F798.0
G1 E563.45
G1 F3000.0
M101
G1 X7.6 Y-9.12 Z8.78 F1800.0 E563.489
G1 X6.13 Y-4.0 Z8.78 F1800.0 E563.749
G1 X6.13 Y6.67 Z8.78 F1800.0 E564.27
G1 X7.6 Y9.12 Z8.78 F1800.0 E564.41
G1 X8.8 Y9.12 Z8.78 F1800.0 E564.468
G1 X8.8 Y-9.12 Z8.78 F1800.0 E565.359
G1 F798.0
G1 E564.859
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P87 (display progress)
(<layer> 9.045 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z9.045 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z9.045 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z9.045 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z9.045 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-8.91 Z9.04 F3000.0
G1 F798.0
G1 E565.159
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z9.04 F1800.0 E565.183
G1 X9.4 Y-9.4 Z9.04 F1800.0 E566.101
G1 X9.4 Y9.4 Z9.04 F1800.0 E567.019
G1 X-9.4 Y9.4 Z9.04 F1800.0 E567.938
G1 X-9.4 Y-8.91 Z9.04 F1800.0 E568.832
G1 F798.0
G1 E568.832
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-8.91 Z9.04 F3000.0
G1 F798.0
G1 E568.832
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z9.04 F900.0 E568.856
G1 X-9.8 Y-9.8 Z9.04 F900.0 E568.875
G1 X9.8 Y-9.8 Z9.04 F900.0 E569.833
G1 X9.8 Y9.8 Z9.04 F900.0 E570.79
G1 X-9.8 Y9.8 Z9.04 F900.0 E571.747
G1 X-9.8 Y-8.91 Z9.04 F900.0 E572.661
G1 F798.0
G1 E572.661
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z9.045 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z9.045 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z9.045 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z9.045 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-9.12 Y-8.4 Z9.04 F3000.0
G1 F798.0
G1 E572.661
G1 F3000.0
M101
G1 X-9.12 Y-4.4 Z9.04 F1800.0 E572.856
G1 X9.12 Y-4.4 Z9.04 F1800.0 E573.747
G1 X9.12 Y-8.8 Z9.04 F1800.0 E573.962
G1 X-9.12 Y-8.8 Z9.04 F1800.0 E574.853
G1 F798.0
G1 E574.353
G1 F1800.0
M103
G1 X9.12 Y7.2 Z9.04 F3000.0
G1 F798.0
G1 E574.653
G1 F3000.0
M101
G1 X9.12 Y-4.0 Z9.04 F1800.0 E575.2
G1 X5.86 Y-4.0 Z9.04 F1800.0 E575.359
G1 X2.14 Y-1.33 Z9.04 F1800.0 E575.583
G1 X1.86 Y-1.33 Z9.04 F1800.0 E575.596
G1 X-1.86 Y-4.0 Z9.04 F1800.0 E575.82
G1 X-2.14 Y-4.0 Z9.04 F1800.0 E575.834
G1 X-5.86 Y-1.33 Z9.04 F1800.0 E576.057
G1 X-6.14 Y-1.33 Z9.04 F1800.0 E576.071
G1 X-9.12 Y-4.0 Z9.04 F1800.0 E576.266
G1 X-9.12 Y7.2 Z9.04 F1800.0 E576.813
G1 F798.0
G1 E576.813
G1 F1800.0
M103
G1 X-9.12 Y8.0 Z9.04 F3000.0
G1 F798.0
G1 E576.813
G1 F3000.0
M101
G1 X-9.12 Y7.6 Z9.04 F1800.0 E576.833
G1 X-6.14 Y4.0 Z9.04 F1800.0 E577.061
G1 X2.14 Y4.0 Z9.04 F1800.0 E577.465
G1 X5.86 Y6.67 Z9.04 F1800.0 E577.689
G1 X6.14 Y6.67 Z9.04 F1800.0 E577.702
G1 X9.12 Y7.6 Z9.04 F1800.0 E577.855
G1 X9.12 Y8.8 Z9.04 F1800.0 E577.914
G1 X-1.86 Y6.67 Z9.04 F1800.0 E578.46
G1 X-2.14 Y6.67 Z9.04 F1800.0 E578.474
G1 X-9.12 Y8.4 Z9.04 F1800.0 E578.825
G1 X-9.12 Y8.8 Z9.04 F1800.0 E578.844
G1 F798.0
G1 E578.344
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P89 (display progress)
(<layer> 9.315 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z9.315 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z9.315 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z9.315 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z9.315 </boundaryPoint>)
(<loop> outer )
G1 X-9.39 Y-9.4 Z9.31 F3000.0
G1 F798.0
G1 E578.644
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z9.31 F1800.0 E579.562
G1 X9.4 Y9.4 Z9.31 F1800.0 E580.48
G1 X-9.4 Y9.4 Z9.31 F1800.0 E581.399
G1 X-9.4 Y-9.4 Z9.31 F1800.0 E582.317
G1 X-9.39 Y-9.4 Z9.31 F1800.0 E582.317
G1 F798.0
G1 E582.317
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.4 Z9.31 F3000.0
G1 F798.0
G1 E582.317
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z9.31 F900.0 E582.336
G1 X9.8 Y-9.8 Z9.31 F900.0 E583.294
G1 X9.8 Y9.8 Z9.31 F900.0 E584.251
G1 X-9.8 Y9.8 Z9.31 F900.0 E585.208
G1 X-9.8 Y-9.4 Z9.31 F900.0 E586.146
G1 X-9.8 Y-9.4 Z9.31 F900.0 E586.146
G1 F798.0
G1 E585.646
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z9.315 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z9.315 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z9.315 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z9.315 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-0.0 Y-9.12 Z9.31 F3000.0
G1 F798.0
G1 E585.946
G1 F3000.0
M101
G1 X0.0 Y9.12 Z9.31 F1800.0 E586.837
G1 X-0.4 Y9.12 Z9.31 F1800.0 E586.856
G1 X-0.4 Y-9.12 Z9.31 F1800.0 E587.747
G1 X-0.8 Y-9.12 Z9.31 F1800.0 E587.767
G1 X-0.8 Y9.12 Z9.31 F1800.0 E588.658
G1 X-1.2 Y9.12 Z9.31 F1800.0 E588.677
G1 X-1.2 Y-9.12 Z9.31 F1800.0 E589.568
G1 X-1.6 Y-9.12 Z9.31 F1800.0 E589.588
G1 X-1.6 Y9.12 Z9.31 F1800.0 E590.478
G1 X-2.0 Y9.12 Z9.31 F1800.0 E590.498
G1 X-2.0 Y-9.12 Z9.31 F1800.0 E591.389
G1 X-2.4 Y-9.12 Z9.31 F1800.0 E591.408
G1 X-2.4 Y9.12 Z9.31 F1800.0 E592.299
G1 X-2.8 Y9.12 Z9.31 F1800.0 E592.319
G1 X-2.8 Y-9.12 Z9.31 F1800.0 E593.21
G1 X-3.2 Y-9.12 Z9.31 F1800.0 E593.229
G1 X-3.2 Y9.12 Z9.31 F1800.0 E594.12
G1 X-3.6 Y9.12 Z9.31 F1800.0 E594.139
G1 X-3.6 Y-9.12 Z9.31 F1800.0 E595.03
G1 X-4.0 Y-9.12 Z9.31 F1800.0 E595.05
G1 X-4.0 Y9.12 Z9.31 F1800.0 E595.941
G1 X-4.4 Y9.12 Z9.31 F1800.0 E595.96
G1 X-4.4 Y-9.12 Z9.31 F1800.0 E596.851
G1 X-4.8 Y-9.12 Z9.31 F1800.0 E596.871
G1 X-4.8 Y9.12 Z9.31 F1800.0 E597.761
G1 X-5.2 Y9.12 Z9.31 F1800.0 E597.781
G1 X-5.2 Y-9.12 Z9.31 F1800.0 E598.672
G1 X-5.6 Y-9.12 Z9.31 F1800.0 E598.691
G1 X-5.6 Y9.12 Z9.31 F1800.0 E599.582
G1 X-6.0 Y9.12 Z9.31 F1800.0 E599.602
G1 X-6.0 Y-9.12 Z9.31 F1800.0 E600.492
G1 X-6.4 Y-9.12 Z9.31 F1800.0 E600.512
G1 X-6.4 Y9.12 Z9.31 F1800.0 E601.403
G1 X-6.8 Y9.12 Z9.31 F1800.0 E601.422
G1 X-6.8 Y-9.12 Z9.31 F1800.0 E602.313
G1 X-7.2 Y-9.12 Z9.31 F1800.0 E602.333
G1 X-7.2 Y9.12 Z9.31 F1800.0 E603.224
G1 X-7.6 Y9.12 Z9.31 F1800.0 E603.243
G1 X-7.6 Y-9.12 Z9.31 F1800.0 E604.134
G1 X-8.0 Y-9.12 Z9.31 F1800.0 E604.154
G1 X-8.0 Y9.12 Z9.31 F1800.0 E605.044
G1 X-8.4 Y9.12 Z9.31 F1800.0 E605.064
G1 X-8.4 Y-9.12 Z9.31 F1800.0 E605.955
G1 X-8.8 Y-9.12 Z9.31 F1800.0 E605.974
G1 X-8.8 Y9.12 Z9.31 F1800.0 E606.865
G1 F798.0
G1 E606.365
G1 F1800.0
M103
G1 X0.4 Y9.12 Z9.31 F3000.0
G1 F798.0
G1 E606.665
G1 F3000.0
M101
G1 X0.4 Y-9.12 Z9.31 F1800.0 E607.556
G1 X0.8 Y-9.12 Z9.31 F1800.0 E607.575
G1 X0.8 Y9.12 Z9.31 F1800.0 E608.466
G1 X1.2 Y9.12 Z9.31 F1800.0 E608.486
G1 X1.2 Y-9.12 Z9.31 F1800.0 E609.377
G1 X1.6 Y-9.12 Z9.31 F1800.0 E609.396
G1 X1.6 Y9.12 Z9.31 F1800.0 E610.287
G1 X2.0 Y9.12 Z9.31 F1800.0 E610.307
G1 X2.0 Y-9.12 Z9.31 F1800.0 E611.197
G1 X2.4 Y-9.12 Z9.31 F1800.0 E611.217
G1 X2.4 Y9.12 Z9.31 F1800.0 E612.108
G1 X2.8 Y9.12 Z9.31 F1800.0 E612.127
G1 X2.8 Y-9.12 Z9.31 F1800.0 E613.018
G1 X3.2 Y-9.12 Z9.31 F1800.0 E613.038
G1 X3.2 Y9.12 Z9.31 F1800.0 E613.929
G1 X3.6 Y9.12 Z9.31 F1800.0 E613.948
G1 X3.6 Y-9.12 Z9.31 F1800.0 E614.839
G1 X4.0 Y-9.12 Z9.31 F1800.0 E614.858
G1 X4.0 Y9.12 Z9.31 F1800.0 E615.749
G1 X4.4 Y9.12 Z9.31 F1800.0 E615.769
G1 X4.4 Y-9.12 Z9.31 F1800.0 E616.66
G1 X4.8 Y-9.12 Z9.31 F1800.0 E616.679
G1 X4.8 Y9.12 Z9.31 F1800.0 E617.57
G1 X5.2 Y9.12 Z9.31 F1800.0 E617.59
G1 X5.2 Y-9.12 Z9.31 F1800.0 E618.48
G1 X5.6 Y-9.12 Z9.31 F1800.0 E618.5
G1 X5.6 Y9.12 Z9.31 F1800.0 E619.391
G1 X6.0 Y9.12 Z9.31 F1800.0 E619.41
G1 X6.0 Y-9.12 Z9.31 F1800.0 E620.301
G1 X6.4 Y-9.12 Z9.31 F1800.0 E620.321
G1 X6.4 Y9.12 Z9.31 F1800.0 E621.211
G1 X6.8 Y9.12 Z9.31 F1800.0 E621.231
G1 X6.8 Y-9.12 Z9.31 F1800.0 E622.122
G1 X7.2 Y-9.12 Z9.31 F1800.0 E622.141
G1 X7.2 Y9.12 Z9.31 F1800.0 E623.032
G1 X7.6 Y9.12 Z9.31 F1800.0 E623.052
G1 X7.6 Y-9.12 Z9.31 F1800.0 E623.943
G1 X8.0 Y-9.12 Z9.31 F1800.0 E623.962
G1 X8.0 Y9.12 Z9.31 F1800.0 E624.853
G1 X8.4 Y9.12 Z9.31 F1800.0 E624.872
G1 X8.4 Y-9.12 Z9.31 F1800.0 E625.763
G1 X8.8 Y-9.12 Z9.31 F1800.0 E625.783
G1 X8.8 Y9.12 Z9.31 F1800.0 E626.674
G1 F798.0
G1 E626.174
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P92 (display progress)
(<layer> 9.585 )
(<rotation> (-1+1.22464679915e-16j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z9.585 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z9.585 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z9.585 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z9.585 </boundaryPoint>)
(<loop> outer )
G1 X-9.4 Y-9.1 Z9.59 F3000.0
G1 F798.0
G1 E626.474
G1 F3000.0
M101
G1 X-9.4 Y-9.4 Z9.59 F1800.0 E626.488
G1 X9.4 Y-9.4 Z9.59 F1800.0 E627.407
G1 X9.4 Y9.4 Z9.59 F1800.0 E628.325
G1 X-9.4 Y9.4 Z9.59 F1800.0 E629.243
G1 X-9.4 Y-9.1 Z9.59 F1800.0 E630.146
G1 F798.0
G1 E630.146
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.1 Z9.59 F3000.0
G1 F798.0
G1 E630.146
G1 F3000.0
M101
G1 X-9.8 Y-9.4 Z9.59 F900.0 E630.161
G1 X-9.8 Y-9.8 Z9.59 F900.0 E630.181
G1 X9.8 Y-9.8 Z9.59 F900.0 E631.138
G1 X9.8 Y9.8 Z9.59 F900.0 E632.095
G1 X-9.8 Y9.8 Z9.59 F900.0 E633.052
G1 X-9.8 Y-9.1 Z9.59 F900.0 E633.975
G1 F798.0
G1 E633.475
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z9.585 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z9.585 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z9.585 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z9.585 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X9.12 Y-0.0 Z9.59 F3000.0
G1 F798.0
G1 E633.775
G1 F3000.0
M101
G1 X-9.12 Y0.0 Z9.59 F1800.0 E634.666
G1 X-9.12 Y-0.4 Z9.59 F1800.0 E634.686
G1 X9.12 Y-0.4 Z9.59 F1800.0 E635.577
G1 X9.12 Y-0.8 Z9.59 F1800.0 E635.596
G1 X-9.12 Y-0.8 Z9.59 F1800.0 E636.487
G1 X-9.12 Y-1.2 Z9.59 F1800.0 E636.507
G1 X9.12 Y-1.2 Z9.59 F1800.0 E637.397
G1 X9.12 Y-1.6 Z9.59 F1800.0 E637.417
G1 X-9.12 Y-1.6 Z9.59 F1800.0 E638.308
G1 X-9.12 Y-2.0 Z9.59 F1800.0 E638.327
G1 X9.12 Y-2.0 Z9.59 F1800.0 E639.218
G1 X9.12 Y-2.4 Z9.59 F1800.0 E639.238
G1 X-9.12 Y-2.4 Z9.59 F1800.0 E640.129
G1 X-9.12 Y-2.8 Z9.59 F1800.0 E640.148
G1 X9.12 Y-2.8 Z9.59 F1800.0 E641.039
G1 X9.12 Y-3.2 Z9.59 F1800.0 E641.058
G1 X-9.12 Y-3.2 Z9.59 F1800.0 E641.949
G1 X-9.12 Y-3.6 Z9.59 F1800.0 E641.969
G1 X9.12 Y-3.6 Z9.59 F1800.0 E642.86
G1 X9.12 Y-4.0 Z9.59 F1800.0 E642.879
G1 X-9.12 Y-4.0 Z9.59 F1800.0 E643.77
G1 X-9.12 Y-4.4 Z9.59 F1800.0 E643.79
G1 X9.12 Y-4.4 Z9.59 F1800.0 E644.68
G1 X9.12 Y-4.8 Z9.59 F1800.0 E644.7
G1 X-9.12 Y-4.8 Z9.59 F1800.0 E645.591
G1 X-9.12 Y-5.2 Z9.59 F1800.0 E645.61
G1 X9.12 Y-5.2 Z9.59 F1800.0 E646.501
G1 X9.12 Y-5.6 Z9.59 F1800.0 E646.521
G1 X-9.12 Y-5.6 Z9.59 F1800.0 E647.411
G1 X-9.12 Y-6.0 Z9.59 F1800.0 E647.431
G1 X9.12 Y-6.0 Z9.59 F1800.0 E648.322
G1 X9.12 Y-6.4 Z9.59 F1800.0 E648.341
G1 X-9.12 Y-6.4 Z9.59 F1800.0 E649.232
G1 X-9.12 Y-6.8 Z9.59 F1800.0 E649.252
G1 X9.12 Y-6.8 Z9.59 F1800.0 E650.143
G1 X9.12 Y-7.2 Z9.59 F1800.0 E650.162
G1 X-9.12 Y-7.2 Z9.59 F1800.0 E651.053
G1 X-9.12 Y-7.6 Z9.59 F1800.0 E651.073
G1 X9.12 Y-7.6 Z9.59 F1800.0 E651.963
G1 X9.12 Y-8.0 Z9.59 F1800.0 E651.983
G1 X-9.12 Y-8.0 Z9.59 F1800.0 E652.874
G1 X-9.12 Y-8.4 Z9.59 F1800.0 E652.893
G1 X9.12 Y-8.4 Z9.59 F1800.0 E653.784
G1 X9.12 Y-8.8 Z9.59 F1800.0 E653.804
G1 X-9.12 Y-8.8 Z9.59 F1800.0 E654.694
G1 F798.0
G1 E654.194
G1 F1800.0
M103
G1 X-9.12 Y0.4 Z9.59 F3000.0
G1 F798.0
G1 E654.494
G1 F3000.0
M101
G1 X9.12 Y0.4 Z9.59 F1800.0 E655.385
G1 X9.12 Y0.8 Z9.59 F1800.0 E655.405
G1 X-9.12 Y0.8 Z9.59 F1800.0 E656.296
G1 X-9.12 Y1.2 Z9.59 F1800.0 E656.315
G1 X9.12 Y1.2 Z9.59 F1800.0 E657.206
G1 X9.12 Y1.6 Z9.59 F1800.0 E657.226
G1 X-9.12 Y1.6 Z9.59 F1800.0 E658.116
G1 X-9.12 Y2.0 Z9.59 F1800.0 E658.136
G1 X9.12 Y2.0 Z9.59 F1800.0 E659.027
G1 X9.12 Y2.4 Z9.59 F1800.0 E659.046
G1 X-9.12 Y2.4 Z9.59 F1800.0 E659.937
G1 X-9.12 Y2.8 Z9.59 F1800.0 E659.957
G1 X9.12 Y2.8 Z9.59 F1800.0 E660.848
G1 X9.12 Y3.2 Z9.59 F1800.0 E660.867
G1 X-9.12 Y3.2 Z9.59 F1800.0 E661.758
G1 X-9.12 Y3.6 Z9.59 F1800.0 E661.777
G1 X9.12 Y3.6 Z9.59 F1800.0 E662.668
G1 X9.12 Y4.0 Z9.59 F1800.0 E662.688
G1 X-9.12 Y4.0 Z9.59 F1800.0 E663.579
G1 X-9.12 Y4.4 Z9.59 F1800.0 E663.598
G1 X9.12 Y4.4 Z9.59 F1800.0 E664.489
G1 X9.12 Y4.8 Z9.59 F1800.0 E664.509
G1 X-9.12 Y4.8 Z9.59 F1800.0 E665.399
G1 X-9.12 Y5.2 Z9.59 F1800.0 E665.419
G1 X9.12 Y5.2 Z9.59 F1800.0 E666.31
G1 X9.12 Y5.6 Z9.59 F1800.0 E666.329
G1 X-9.12 Y5.6 Z9.59 F1800.0 E667.22
G1 X-9.12 Y6.0 Z9.59 F1800.0 E667.24
G1 X9.12 Y6.0 Z9.59 F1800.0 E668.13
G1 X9.12 Y6.4 Z9.59 F1800.0 E668.15
G1 X-9.12 Y6.4 Z9.59 F1800.0 E669.041
G1 X-9.12 Y6.8 Z9.59 F1800.0 E669.06
G1 X9.12 Y6.8 Z9.59 F1800.0 E669.951
G1 X9.12 Y7.2 Z9.59 F1800.0 E669.971
G1 X-9.12 Y7.2 Z9.59 F1800.0 E670.862
G1 X-9.12 Y7.6 Z9.59 F1800.0 E670.881
G1 X9.12 Y7.6 Z9.59 F1800.0 E671.772
G1 X9.12 Y8.0 Z9.59 F1800.0 E671.791
G1 X-9.12 Y8.0 Z9.59 F1800.0 E672.682
G1 X-9.12 Y8.4 Z9.59 F1800.0 E672.702
G1 X9.12 Y8.4 Z9.59 F1800.0 E673.593
G1 X9.12 Y8.8 Z9.59 F1800.0 E673.612
G1 X-9.12 Y8.8 Z9.59 F1800.0 E674.503
G1 F798.0
G1 E674.003
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
M73 P96 (display progress)
(<layer> 9.855 )
(<rotation> (6.12323399574e-17+1j) )
(<nestedRing>)
(<boundaryPerimeter>)
(<boundaryPoint> X-10.0 Y-10.0 Z9.855 </boundaryPoint>)
(<boundaryPoint> X10.0 Y-10.0 Z9.855 </boundaryPoint>)
(<boundaryPoint> X10.0 Y10.0 Z9.855 </boundaryPoint>)
(<boundaryPoint> X-10.0 Y10.0 Z9.855 </boundaryPoint>)
(<loop> outer )
G1 X-9.21 Y-9.4 Z9.86 F3000.0
G1 F798.0
G1 E674.303
G1 F3000.0
M101
G1 X9.4 Y-9.4 Z9.86 F1800.0 E675.212
G1 X9.4 Y9.4 Z9.86 F1800.0 E676.13
G1 X-9.4 Y9.4 Z9.86 F1800.0 E677.048
G1 X-9.4 Y-9.4 Z9.86 F1800.0 E677.966
G1 X-9.21 Y-9.4 Z9.86 F1800.0 E677.976
G1 F798.0
G1 E677.976
G1 F1800.0
M103
(</loop>)
(<perimeter> outer )
;M108 R15.0
G1 X-9.8 Y-9.59 Z9.86 F3000.0
G1 F798.0
G1 E677.976
G1 F3000.0
M101
G1 X-9.8 Y-9.8 Z9.86 F900.0 E677.986
G1 X9.8 Y-9.8 Z9.86 F900.0 E678.943
G1 X9.8 Y9.8 Z9.86 F900.0 E679.9
G1 X-9.8 Y9.8 Z9.86 F900.0 E680.858
G1 X-9.8 Y-9.4 Z9.86 F900.0 E681.795
G1 X-9.8 Y-9.59 Z9.86 F900.0 E681.805
G1 F798.0
G1 E681.305
G1 F900.0
M103
(</perimeter>)
(</boundaryPerimeter>)
(<infill>)
(<infillBoundary>)
(<infillPoint> X-9.4 Y-9.4 Z9.855 </infillPoint>)
(<infillPoint> X9.4 Y-9.4 Z9.855 </infillPoint>)
(<infillPoint> X9.4 Y9.4 Z9.855 </infillPoint>)
(<infillPoint> X-9.4 Y9.4 Z9.855 </infillPoint>)
(</infillBoundary>)
;M108 R30.0
G1 X-0.0 Y-9.12 Z9.86 F3000.0
G1 F798.0
G1 E681.605
G1 F3000.0
M101
G1 X0.0 Y9.12 Z9.86 F1800.0 E682.496
G1 X-0.4 Y9.12 Z9.86 F1800.0 E682.515
G1 X-0.4 Y-9.12 Z9.86 F1800.0 E683.406
G1 X-0.8 Y-9.12 Z9.86 F1800.0 E683.426
G1 X-0.8 Y9.12 Z9.86 F1800.0 E684.316
G1 X-1.2 Y9.12 Z9.86 F1800.0 E684.336
G1 X-1.2 Y-9.12 Z9.86 F1800.0 E685.227
G1 X-1.6 Y-9.12 Z9.86 F1800.0 E685.246
G1 X-1.6 Y9.12 Z9.86 F1800.0 E686.137
G1 X-2.0 Y9.12 Z9.86 F1800.0 E686.157
G1 X-2.0 Y-9.12 Z9.86 F1800.0 E687.048
G1 X-2.4 Y-9.12 Z9.86 F1800.0 E687.067
G1 X-2.4 Y9.12 Z9.86 F1800.0 E687.958
G1 X-2.8 Y9.12 Z9.86 F1800.0 E687.977
G1 X-2.8 Y-9.12 Z9.86 F1800.0 E688.868
G1 X-3.2 Y-9.12 Z9.86 F1800.0 E688.888
G1 X-3.2 Y9.12 Z9.86 F1800.0 E689.779
G1 X-3.6 Y9.12 Z9.86 F1800.0 E689.798
G1 X-3.6 Y-9.12 Z9.86 F1800.0 E690.689
G1 X-4.0 Y-9.12 Z9.86 F1800.0 E690.709
G1 X-4.0 Y9.12 Z9.86 F1800.0 E691.599
G1 X-4.4 Y9.12 Z9.86 F1800.0 E691.619
G1 X-4.4 Y-9.12 Z9.86 F1800.0 E692.51
G1 X-4.8 Y-9.12 Z9.86 F1800.0 E692.529
G1 X-4.8 Y9.12 Z9.86 F1800.0 E693.42
G1 X-5.2 Y9.12 Z9.86 F1800.0 E693.44
G1 X-5.2 Y-9.12 Z9.86 F1800.0 E694.33
G1 X-5.6 Y-9.12 Z9.86 F1800.0 E694.35
G1 X-5.6 Y9.12 Z9.86 F1800.0 E695.241
G1 X-6.0 Y9.12 Z9.86 F1800.0 E695.26
G1 X-6.0 Y-9.12 Z9.86 F1800.0 E696.151
G1 X-6.4 Y-9.12 Z9.86 F1800.0 E696.171
G1 X-6.4 Y9.12 Z9.86 F1800.0 E697.062
G1 X-6.8 Y9.12 Z9.86 F1800.0 E697.081
G1 X-6.8 Y-9.12 Z9.86 F1800.0 E697.972
G1 X-7.2 Y-9.12 Z9.86 F1800.0 E697.991
G1 X-7.2 Y9.12 Z9.86 F1800.0 E698.882
G1 X-7.6 Y9.12 Z9.86 F1800.0 E698.902
G1 X-7.6 Y-9.12 Z9.86 F1800.0 E699.793
G1 X-8.0 Y-9.12 Z9.86 F1800.0 E699.812
G1 X-8.0 Y9.12 Z9.86 F1800.0 E700.703
G1 X-8.4 Y9.12 Z9.86 F1800.0 E700.723
G1 X-8.4 Y-9.12 Z9.86 F1800.0 E701.613
G1 X-8.8 Y-9.12 Z9.86 F1800.0 E701.633
G1 X-8.8 Y9.12 Z9.86 F1800.0 E702.524
G1 F798.0
G1 E702.024
G1 F1800.0
M103
G1 X0.4 Y9.12 Z9.86 F3000.0
G1 F798.0
G1 E702.324
G1 F3000.0
M101
G1 X0.4 Y-9.12 Z9.86 F1800.0 E703.215
G1 X0.8 Y-9.12 Z9.86 F1800.0 E703.234
G1 X0.8 Y9.12 Z9.86 F1800.0 E704.125
G1 X1.2 Y9.12 Z9.86 F1800.0 E704.145
G1 X1.2 Y-9.12 Z9.86 F1800.0 E705.035
G1 X1.6 Y-9.12 Z9.86 F1800.0 E705.055
G1 X1.6 Y9.12 Z9.86 F1800.0 E705.946
G1 X2.0 Y9.12 Z9.86 F1800.0 E705.965
G1 X2.0 Y-9.12 Z9.86 F1800.0 E706.856
G1 X2.4 Y-9.12 Z9.86 F1800.0 E706.876
G1 X2.4 Y9.12 Z9.86 F1800.0 E707.766
G1 X2.8 Y9.12 Z9.86 F1800.0 E707.786
G1 X2.8 Y-9.12 Z9.86 F1800.0 E708.677
G1 X3.2 Y-9.12 Z9.86 F1800.0 E708.696
G1 X3.2 Y9.12 Z9.86 F1800.0 E709.587
G1 X3.6 Y9.12 Z9.86 F1800.0 E709.607
G1 X3.6 Y-9.12 Z9.86 F1800.0 E710.498
G1 X4.0 Y-9.12 Z9.86 F1800.0 E710.517
G1 X4.0 Y9.12 Z9.86 F1800.0 E711.408
G1 X4.4 Y9.12 Z9.86 F1800.0 E711.428
G1 X4.4 Y-9.12 Z9.86 F1800.0 E712.318
G1 X4.8 Y-9.12 Z9.86 F1800.0 E712.338
G1 X4.8 Y9.12 Z9.86 F1800.0 E713.229
G1 X5.2 Y9.12 Z9.86 F1800.0 E713.248
G1 X5.2 Y-9.12 Z9.86 F1800.0 E714.139
G1 X5.6 Y-9.12 Z9.86 F1800.0 E714.159
G1 X5.6 Y9.12 Z9.86 F1800.0 E715.049
G1 X6.0 Y9.12 Z9.86 F1800.0 E715.069
G1 X6.0 Y-9.12 Z9.86 F1800.0 E715.96
G1 X6.4 Y-9.12 Z9.86 F1800.0 E715.979
G1 X6.4 Y9.12 Z9.86 F1800.0 E716.87
G1 X6.8 Y9.12 Z9.86 F1800.0 E716.89
G1 X6.8 Y-9.12 Z9.86 F1800.0 E717.781
G1 X7.2 Y-9.12 Z9.86 F1800.0 E717.8
G1 X7.2 Y9.12 Z9.86 F1800.0 E718.691
G1 X7.6 Y9.12 Z9.86 F1800.0 E718.71
G1 X7.6 Y-9.12 Z9.86 F1800.0 E719.601
G1 X8.0 Y-9.12 Z9.86 F1800.0 E719.621
G1 X8.0 Y9.12 Z9.86 F1800.0 E720.512
G1 X8.4 Y9.12 Z9.86 F1800.0 E720.531
G1 X8.4 Y-9.12 Z9.86 F1800.0 E721.422
G1 X8.8 Y-9.12 Z9.86 F1800.0 E721.442
G1 X8.8 Y9.12 Z9.86 F1800.0 E722.332
G1 F798.0
G1 E721.832
G1 F1800.0
M103
(</infill>)
(</nestedRing>)
(</rotation>)
(</layer>)
(</crafting>)
M104 S0
;M113 S0.0
