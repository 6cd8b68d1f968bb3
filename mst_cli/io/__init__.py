"""Files in and out: the YAML schema and loader, reports and tables, atomic output folders,
serial-line parsing. Depends on the model, never on design, CAD or the command line."""
