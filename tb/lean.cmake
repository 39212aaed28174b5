# cnc_core's lean build (rtl/cnc_core.v build options): 2 axes, protocol v1 only (no
# frame_decoder, FIFO, response_encoder, profiles, arcs or heaters), the configuration
# scripts/synth_report.sh reports as "lean". A short v1 job through its pins (~1 s).
fpgacnc_verilated(vcore_lean TOP cnc_core PREFIX Vcnc_core_lean
                  SOURCES ${FPGACNC_CORE_RTL} ${FPGACNC_RTL_DIR}/packet_decoder_v1.v
                  ARGS -GN_AXES=2 -GPROTO_V2=0)
fpgacnc_bench(test_cnc_core_lean LABEL system
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_cnc_core_lean.cpp LIBS vcore_lean fmt::fmt)
# The v2 build without profiles, arcs and heaters (2 axes): their frames are unknown types.
fpgacnc_verilated(vcore_lines TOP cnc_core PREFIX Vcnc_core_lines SOURCES ${FPGACNC_CORE_RTL}
                  ARGS -GN_AXES=2 -GPROFILES=0 -GARCS=0 -GHEATERS=0)
target_link_libraries(test_cnc_core_lean PRIVATE vcore_lines)
# Lockstep pair for the lean trims (rtl/cnc_core.v LEAN_TRIM, STEP_CFG): the lean build with the
# v1 datapath trims (vcore_lean_fast), without them (vcore_lean_ref) and with the step timing fixed
# (vcore_lean_fixed), all with a fast UART (20 clocks a bit), a short watchdog and short step
# timing, so a random v1 session of many moves takes ~1 M clocks.
set(_lean_fast -GN_AXES=2 -GPROTO_V2=0 -GBAUD=2500000 -GWATCHDOG_CLKS=20000 -GFEED0_PERIOD=700
               -GDEFAULT_NUMERATOR=150000 -GSTEP_HIGH=3 -GSTEP_LOW=2 -GDIR_SETUP=6 -GDIR_HOLD=4)
fpgacnc_verilated(vcore_lean_fast TOP cnc_core PREFIX Vcnc_core_lean_fast
                  SOURCES ${FPGACNC_CORE_RTL} ${FPGACNC_RTL_DIR}/packet_decoder_v1.v
                  ARGS ${_lean_fast})
fpgacnc_verilated(vcore_lean_ref TOP cnc_core PREFIX Vcnc_core_lean_ref
                  SOURCES ${FPGACNC_CORE_RTL} ${FPGACNC_RTL_DIR}/packet_decoder_v1.v
                  ARGS ${_lean_fast} -GLEAN_TRIM=0)
fpgacnc_verilated(vcore_lean_fixed TOP cnc_core PREFIX Vcnc_core_lean_fixed
                  SOURCES ${FPGACNC_CORE_RTL} ${FPGACNC_RTL_DIR}/packet_decoder_v1.v
                  ARGS ${_lean_fast} -GSTEP_CFG=0)
target_link_libraries(test_cnc_core_lean PRIVATE vcore_lean_fast vcore_lean_ref vcore_lean_fixed)
