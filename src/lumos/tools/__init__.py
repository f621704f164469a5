"""Tools on top of the API, one command each: `sheet` (`lumos sheet`: every method side by side, and
`sheet_drawing`, its grid and captions), `explain` (`lumos explain`: what made one pixel), `metrics`
(`lumos compare`: how two images differ) and `warmup` (`lumos warmup`: every kernel compiled now).

They use `lumos.render` and the scene model like any program would; nothing below imports them.
"""
