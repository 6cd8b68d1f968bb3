"""The physics of one sensor: pure kernels, no files, no command line.

cell and assembly (the geometry), components (board and magnet catalogue), material, mechanics
(the L0/L1/L2 layer ladder), magnet_field (magnet models), chip (MLX90393 settings and
resolution), stack (layers in series), response (force -> displacement -> field), offcentre (a
press off the axis), ladder (picking a rung from a requested accuracy), file_keys (declaring a
file key once, with its unit and bounds). See docs/design.md.
"""
