# UART bench: uart_rx and uart_tx Verilated once per tested baud rate (CLK_HZ 50 MHz), wired
# together (txd -> rxd) or driven by UartDriver in C++.
set(_uart_libs)
foreach(_baud 115200 1000000 3000000)
  foreach(_mod uart_rx uart_tx)
    fpgacnc_verilated(${_mod}_${_baud} TOP ${_mod} PREFIX V${_mod}_${_baud}
                      SOURCES ${FPGACNC_RTL_DIR}/protocol/${_mod}.v
                      ARGS -GCLK_HZ=50000000 -GBAUD=${_baud})
    list(APPEND _uart_libs ${_mod}_${_baud})
  endforeach()
endforeach()
fpgacnc_bench(test_uart LABEL rtl SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/test_uart.cpp
              LIBS ${_uart_libs})
