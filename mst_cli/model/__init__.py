"""The physics of one sensor: pure kernels, no files, no command line.

geometry (the cell and the assembly), components (board and magnet catalogue), material,
mechanics (the L0/L1/L2 layer ladder), field (magnet models), chip (MLX90393 settings and
resolution), stack (layers in series), response (force -> displacement -> field), ladder
(picking a rung from a requested accuracy). See docs/design.md.
"""
