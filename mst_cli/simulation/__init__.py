"""What ``mst simulate`` writes: report.json, response.csv and the plots of a design's forward
model, and the off-centre files. The physics is the model's (:mod:`mst_cli.model.response`,
:mod:`mst_cli.model.offcentre`) on the part as printed (:mod:`mst_cli.sensor.as_printed`)."""
