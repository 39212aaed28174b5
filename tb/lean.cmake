# cnc_core's lean build (rtl/cnc_core.v build options): 2 axes, protocol v1 only (no
# frame_decoder, FIFO, response_encoder, profiles, arcs or heaters), the configuration
# scripts/synth_report.sh reports as "lean". A short v1 job through its pins (~1 s).
fpgacnc_verilated(vcore_lean TOP cnc_core PREFIX Vcnc_core_lean
                  SOURCES ${FPGACNC_CORE_RTL} ${FPGACNC_RTL_DIR}/packet_decoder_v1.v
                  ARGS -GN_AXES=2 -GPROTO_V2=0)
fpgacnc_bench(test_cnc_core_lean LABEL system
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_cnc_core_lean.cpp LIBS vcore_lean fmt::fmt)
