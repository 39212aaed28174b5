; Bed warm-up as the user sees it (docs/images/bed-warmup.svg, `make heater-plot`): 20 -> 60 degC
; with the reference bed tuning, held for the settle time of examples/bed-warmup.toml, then off.
M140 S60
M190 S60
M140 S0
