"""File plumbing: the size-capped YAML loader, input rules read from declared keys, atomic output
folders, serial-line parsing. Depends on the model, never on the sensor description, design,
CAD or the command line (each file format lives beside the concept it serialises)."""
