# Decoder, system benches (cnc_core and the DE1-SoC top through their pins) and the core
# benchmark. The Verilated models (vframe, vfifo, vencoder, vcore, vde1soc, vexec) come from core.cmake.
fpgacnc_bench(test_frame_decoder LABEL rtl
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_frame_decoder.cpp LIBS vframe fmt::fmt)
fpgacnc_bench(test_segment_fifo LABEL rtl
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_segment_fifo.cpp LIBS vfifo fmt::fmt)
fpgacnc_bench(test_response_encoder LABEL rtl
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_response_encoder.cpp
              LIBS vencoder vcrc fmt::fmt)
fpgacnc_bench(test_cnc_core LABEL system
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_cnc_core.cpp LIBS vcore fmt::fmt)
fpgacnc_bench(test_cnc_core_v2 LABEL system
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_cnc_core_v2.cpp LIBS vcore_heat fmt::fmt)
fpgacnc_bench(test_feed_hold LABEL system
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_feed_hold.cpp LIBS vcore_heat fmt::fmt)
fpgacnc_bench(test_de1soc_top LABEL system
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_de1soc_top.cpp LIBS vde1soc fmt::fmt)

# Benchmark (not a test): step timing accuracy, Verilator speed, maximum step rate.
add_executable(bench_core ${CMAKE_CURRENT_SOURCE_DIR}/bench_core.cpp)
fpgacnc_warnings(bench_core)
target_include_directories(bench_core PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
target_link_libraries(bench_core PRIVATE vcore vexec fpgacnc_spec fpgacnc_models fmt::fmt)

# Protocol benchmark (make bench; not built by `make` / `make test`): v1 stop-and-wait against
# the v2 sliding window with the host's streamers, through the pins at 115 200 and 1 000 000 baud.
if(FPGACNC_BUILD_HOST)
  fpgacnc_verilated(vcore_1m TOP cnc_core PREFIX Vcnc_core_1m CONFIG full-4axis
                    SOURCES ${FPGACNC_CORE_RTL} ARGS -GBAUD=1000000)
  set_target_properties(vcore_1m PROPERTIES EXCLUDE_FROM_ALL ON)
  add_executable(bench_protocol EXCLUDE_FROM_ALL ${CMAKE_CURRENT_SOURCE_DIR}/bench_protocol.cpp)
  fpgacnc_warnings(bench_protocol)
  target_include_directories(bench_protocol PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(bench_protocol PRIVATE vcore vcore_1m fpgacnc_host fpgacnc_models fmt::fmt)
endif()
# The worked sequences of spec/vectors.txt through cnc_core's pins (coalesced NAKs).
fpgacnc_bench(test_spec_sequences LABEL system
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_spec_sequences.cpp LIBS vcore fmt::fmt)
