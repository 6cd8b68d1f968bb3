"""From a printed sensor's load test to forces: the load-test parser (loadtest), the
least-squares fit of the model's print parameters (fit) and, for the next design, the fitted
printer read back from calibration.json (record)."""
