# Verilated models of the core blocks, shared by the benches, the simulated board and the
# benchmarks.
fpgacnc_verilated(vexec TOP segment_executor
                  SOURCES ${FPGACNC_RTL_DIR}/motion/segment_executor.v ${FPGACNC_RTL_DIR}/motion/axis_channel.v
                          ${FPGACNC_RTL_DIR}/motion/dir_sequencer.v ${FPGACNC_RTL_DIR}/motion/dda_linear.v
                          ${FPGACNC_RTL_DIR}/motion/profile_gen.v ${FPGACNC_RTL_DIR}/motion/dda_profile.v
                          ${FPGACNC_RTL_DIR}/motion/arc_dda.v
                          ${FPGACNC_RTL_DIR}/motion/step_pulse.v)
fpgacnc_verilated(vprep TOP segment_prep
                  SOURCES ${FPGACNC_RTL_DIR}/motion/segment_prep.v ${FPGACNC_RTL_DIR}/motion/prep_profile.v
                          ${FPGACNC_RTL_DIR}/motion/prep_arc.v ${FPGACNC_RTL_DIR}/motion/prep_dir_tracker.v)
fpgacnc_verilated(vframe TOP frame_decoder
                  SOURCES ${FPGACNC_RTL_DIR}/protocol/frame_decoder.v ${FPGACNC_RTL_DIR}/protocol/frame_fields.v
                          ${FPGACNC_RTL_DIR}/protocol/entry_pack.v ${FPGACNC_RTL_DIR}/protocol/crc16_ccitt.v
                          ${FPGACNC_RTL_DIR}/machine/travel_guard.v)
fpgacnc_verilated(vfifo TOP segment_fifo SOURCES ${FPGACNC_RTL_DIR}/protocol/segment_fifo.v
                  ARGS -GWIDTH=40 -GDEPTH=16)
fpgacnc_verilated(vcrc TOP crc16_ccitt SOURCES ${FPGACNC_RTL_DIR}/protocol/crc16_ccitt.v)
fpgacnc_verilated(vencoder TOP response_encoder
                  SOURCES ${FPGACNC_RTL_DIR}/protocol/response_encoder.v ${FPGACNC_RTL_DIR}/protocol/crc16_ccitt.v)
fpgacnc_verilated(vcore TOP cnc_core CONFIG full-4axis PGO SOURCES ${FPGACNC_CORE_RTL})
# cnc_core at 3 Mbaud (fast UART, same RTL) with the heaters' sample tick scaled to 4096 clocks
# and their PWM to 1024 clocks: the v2 system benches (test_cnc_core_v2, test_feed_hold,
# test_profile, test_arc_core) and the heater core bench (tb/heater.cmake). Heaters stay off
# unless a bench configures them.
fpgacnc_verilated(vcore_heat TOP cnc_core PREFIX Vcnc_core_heat CONFIG full-4axis
                  SOURCES ${FPGACNC_CORE_RTL}
                  ARGS -GBAUD=3000000 -GSAMPLE_CLKS=${FPGACNC_SPEC_BENCH_SAMPLE_CLKS} -GHEAT_PWM_DIV=1)
# The DE1-SoC top: its cnc_core is the configuration full-2axis (spec/configs.toml).
fpgacnc_verilated(vde1soc TOP de1soc_top
                  SOURCES ${FPGACNC_CORE_RTL} ${FPGACNC_RTL_DIR}/board/hex7seg.v
                          ${FPGACNC_RTL_DIR}/board/de1soc_top.v
                  ARGS -GCLK_HZ=50000000)

fpgacnc_bench(test_segment_executor LABEL rtl
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_segment_executor.cpp LIBS vexec vprep fmt::fmt)
fpgacnc_bench(test_segment_prep LABEL rtl
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_segment_prep.cpp LIBS vprep fmt::fmt)
fpgacnc_bench(test_profile LABEL rtl
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_profile.cpp LIBS vexec vprep vcore_heat fmt::fmt)
