"""Measuring the speed/accuracy ladder (``mst bench``): sampling, timing and error tables."""
