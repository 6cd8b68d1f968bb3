"""From a reading to the load: the estimators and what they share. The inverse map of |B| to
the force (:mod:`~mst_cli.estimation.inverse_map`), the exact offset and shear solves on the
model (:mod:`~mst_cli.estimation.offset_reading`, :mod:`~mst_cli.estimation.shear_reading`), the
one-chip tables and their direct inverse (:mod:`~mst_cli.estimation.inverse_table`), the
two-chip reader (:mod:`~mst_cli.estimation.two_chip_table`) and the estimates they return
(:mod:`~mst_cli.estimation.load_readings`). Pure physics on the model's laws, above the sensor
layer; no command line."""
