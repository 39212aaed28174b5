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
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_cnc_core_v2.cpp LIBS vcore_3m fmt::fmt)
fpgacnc_bench(test_de1soc_top LABEL system
              SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_de1soc_top.cpp LIBS vde1soc fmt::fmt)

# Benchmark (not a test): step timing accuracy, Verilator speed, maximum step rate.
add_executable(bench_core ${CMAKE_CURRENT_SOURCE_DIR}/bench_core.cpp)
fpgacnc_warnings(bench_core)
target_include_directories(bench_core PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
target_link_libraries(bench_core PRIVATE vcore vexec fmt::fmt)
