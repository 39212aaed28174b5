# cnc_core's reduced configurations (spec/configs.toml; rtl/cnc_core.v build options).
# v1-board: 2 axes, protocol v1 only (no frame_decoder, FIFO, response_encoder, profiles, arcs or
# heaters). A short v1 job through its pins (~1 s).
fpgacnc_verilated(vcore_v1_board TOP cnc_core PREFIX Vcnc_core_v1_board CONFIG v1-board
                  SOURCES ${FPGACNC_CORE_RTL} ${FPGACNC_RTL_DIR}/protocol/packet_decoder_v1.v
                          ${FPGACNC_RTL_DIR}/protocol/front_v1.v)
fpgacnc_bench(test_cnc_core_lean LABEL system
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_cnc_core_lean.cpp LIBS vcore_v1_board fmt::fmt)
# lines-2axis: v2 without profiles, arcs and heaters; their frames are unknown types.
fpgacnc_verilated(vcore_lines_2axis TOP cnc_core PREFIX Vcnc_core_lines_2axis CONFIG lines-2axis
                  SOURCES ${FPGACNC_CORE_RTL})
target_link_libraries(test_cnc_core_lean PRIVATE vcore_lines_2axis)
# Lockstep pair for the v1 trims (rtl/cnc_core.v LEAN_TRIM, STEP_CFG): v1-board with the v1
# datapath trims (vcore_v1_board_fast), v1-board-untrimmed (without them) and v1-board-fixed (the
# step timing fixed), all with a fast UART (20 clocks a bit), a short watchdog and short step
# timing, so a random v1 session of many moves takes ~1 M clocks.
set(_fast_timing -GBAUD=2500000 -GWATCHDOG_CLKS=20000 -GFEED0_PERIOD=700 -GDEFAULT_NUMERATOR=150000
                 -GSTEP_HIGH=3 -GSTEP_LOW=2 -GDIR_SETUP=6 -GDIR_HOLD=4)
fpgacnc_verilated(vcore_v1_board_fast TOP cnc_core PREFIX Vcnc_core_v1_board_fast CONFIG v1-board
                  SOURCES ${FPGACNC_CORE_RTL} ${FPGACNC_RTL_DIR}/protocol/packet_decoder_v1.v
                          ${FPGACNC_RTL_DIR}/protocol/front_v1.v
                  ARGS ${_fast_timing})
fpgacnc_verilated(vcore_v1_board_untrimmed_fast TOP cnc_core
                  PREFIX Vcnc_core_v1_board_untrimmed_fast CONFIG v1-board-untrimmed
                  SOURCES ${FPGACNC_CORE_RTL} ${FPGACNC_RTL_DIR}/protocol/packet_decoder_v1.v
                          ${FPGACNC_RTL_DIR}/protocol/front_v1.v
                  ARGS ${_fast_timing})
fpgacnc_verilated(vcore_v1_board_fixed_fast TOP cnc_core PREFIX Vcnc_core_v1_board_fixed_fast
                  CONFIG v1-board-fixed
                  SOURCES ${FPGACNC_CORE_RTL} ${FPGACNC_RTL_DIR}/protocol/packet_decoder_v1.v
                          ${FPGACNC_RTL_DIR}/protocol/front_v1.v
                  ARGS ${_fast_timing})
target_link_libraries(test_cnc_core_lean PRIVATE vcore_v1_board_fast vcore_v1_board_untrimmed_fast
                                                 vcore_v1_board_fixed_fast)
