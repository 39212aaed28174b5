// CLI glue for the simulated board (board command, default link for stream): see cli_board.h.
