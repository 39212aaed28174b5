# Open-tool synthesis checks (label synth).
# The Yosys resource reports of the configurations v1-board and full-2axis (the DE1-SoC board)
# against constraints/resource_budget.txt are `make synth-budget`'s, which CI runs as its own step
# beside `make formal` (about 4 CPU-minutes of Yosys); full-4axis and v1-board-fixed are `make
# synth`'s. Every RTL file is still read and checked by Yosys in `make test` (rtl_lint).

# ice40_timing (Yosys synth_ice40 + nextpnr-ice40 of the v1-board configuration, ~30 s) is `make
# synth`'s, with the strict block report, to keep `make test` within its CI budget.

# check_qsf: the Quartus project lists exactly de1soc_top's RTL files and every top port has a pin
# and an I/O standard (scripts/check_qsf.sh; a few seconds).
add_test(NAME check_qsf
         COMMAND ${CMAKE_SOURCE_DIR}/scripts/check_qsf.sh
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(check_qsf PROPERTIES LABELS synth TIMEOUT 120)
