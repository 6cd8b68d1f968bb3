"""mst: design tool for multi-sensitivity soft tactile sensors."""

__version__ = "0.6.0"
