"""From a printed sensor's load test to forces: the load-test parser (loadtest) and the
least-squares fit of the model's print parameters (fit)."""
