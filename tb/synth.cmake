# Open-tool synthesis reports (label synth), beside synth_smoke_cyclonev in the top CMakeLists.txt.
# synth_report: Yosys synth_intel_alm resource report for the DE1-SoC top (2 axes) and cnc_core
#   with 4 axes, checked against constraints/resource_budget.txt (~25 s on 2 cores).
# ice40_timing: Yosys synth_ice40 + nextpnr-ice40 (HX8K ct256) at 50 MHz for 4 and 2 axes; fails
#   below 50 MHz (~65-90 s on 2 cores). Needs the Debian package nextpnr-ice40. As of 2026-11-21 it
#   fails (33.4 MHz with 4 axes, 44.7 MHz with 2): see docs/synthesis.md, critical paths.
add_test(NAME synth_report
         COMMAND ${CMAKE_SOURCE_DIR}/scripts/synth_report.sh ${CMAKE_BINARY_DIR}/synth
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(synth_report PROPERTIES LABELS synth TIMEOUT 600)

add_test(NAME ice40_timing
         COMMAND ${CMAKE_SOURCE_DIR}/scripts/ice40_timing.sh ${CMAKE_BINARY_DIR}/synth
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(ice40_timing PROPERTIES LABELS synth TIMEOUT 600)
