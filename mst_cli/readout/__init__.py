"""``mst read``'s readout: a readings file or a live stream's lines to forces.csv through the one
reading pipeline (:meth:`mst_cli.readout.reading.ForceReader.read`; a live stream in batches,
:mod:`~mst_cli.readout.live`), a rig's stream with tare, zero tracking and branch following
(:mod:`~mst_cli.readout.rig_reading`). Above the calibration layer, below the api."""
