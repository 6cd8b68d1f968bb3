"""C99 headers for a microcontroller that reads the MLX90393: the calibrated Z code -> force table
(:mod:`~mst_cli.firmware.header`, ``force_table.h``) and the one-chip table readers
(:mod:`~mst_cli.firmware.table_header`, ``offset_table.h`` / ``shear_table.h``), filled from
templates in package data (``data/*.h.in``). Above the estimation layer, whose maps and tables
they tabulate."""
