# The G-code front end's sources, relative to host/: the host library (host/CMakeLists.txt) and
# the fuzz build (fuzz/CMakeLists.txt, which compiles them itself with sanitizers) both read this
# list, so a new file of the interpreter reaches both.
set(FPGACNC_HOST_GCODE_SOURCES
    src/gcode/dialect.cpp
    src/gcode/interpreter.cpp
    src/gcode/cutter_comp.cpp
    src/gcode/reader.cpp
    src/gcode/tool_table.cpp
    src/gcode/expr.cpp)

# The protocol v2 codec (fpgacnc/protocol/v2.h), one file per frame family: the host library and
# the fuzz build (fuzz_v2_codec) both read this list.
set(FPGACNC_HOST_V2_CODEC_SOURCES
    src/protocol/v2_frame.cpp
    src/protocol/v2_control.cpp
    src/protocol/v2_motion.cpp
    src/protocol/v2_heater.cpp
    src/protocol/v2_check.cpp)
