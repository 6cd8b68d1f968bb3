"""``mst read``'s readout: a live stream's lines to the one reading pipeline
(:meth:`mst_cli.calibrate.reading.ForceReader.read`), in batches. Above the calibration layer,
below the api."""
