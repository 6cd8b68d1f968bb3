"""From a printed sensor's load test to the fitted print (``mst calibrate``): the load-test
parser (:mod:`~mst_cli.calibration.loadtest`), the least-squares fit of the model's print
parameters (:mod:`~mst_cli.calibration.fit`), the rig's analysis (branches, hysteresis,
softening, creep and the zero's drift, the force's lag, its unit, rows without a force), the
tilt and temperature fits, the calibration's record (calibration.json, read back strictly by
``mst design --calibration``) and its CSV tables. Above the estimation and firmware layers (a
calibration writes the inverse map, the tables and the headers), below the readout."""
