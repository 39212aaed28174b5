# Open-tool synthesis checks (label synth).
# synth_report: Yosys synth_intel_alm resource report of the configuration v1-board (cnc_core,
#   2 axes, v1 only; spec/configs.toml), checked against constraints/resource_budget.txt; also
#   fails on a Yosys warning. The DE1-SoC board (full-2axis, about 3 CPU-minutes of Yosys) is
#   `make synth-budget`'s, which CI runs as its own step beside `make formal`; full-4axis and
#   v1-board-fixed are `make synth`'s. SYNTH_NAMES=0: without Yosys's autoname pass (the same
#   cells; names only matter to the longest path's printout, which `make synth` prints with them).
add_test(NAME synth_report
         COMMAND ${CMAKE_COMMAND} -E env CONFIGS=v1-board SYNTH_NAMES=0
                 ${CMAKE_SOURCE_DIR}/scripts/synth_report.sh ${CMAKE_BINARY_DIR}/synth
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(synth_report PROPERTIES LABELS synth TIMEOUT 600 COST 100)

# ice40_timing (Yosys synth_ice40 + nextpnr-ice40 of the v1-board configuration, ~30 s) is `make
# synth`'s, with the strict block report, to keep `make test` within its CI budget.

# check_qsf: the Quartus project lists exactly de1soc_top's RTL files and every top port has a pin
# and an I/O standard (scripts/check_qsf.sh; a few seconds).
add_test(NAME check_qsf
         COMMAND ${CMAKE_SOURCE_DIR}/scripts/check_qsf.sh
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(check_qsf PROPERTIES LABELS synth TIMEOUT 120)
