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
