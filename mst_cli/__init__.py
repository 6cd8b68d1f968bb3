"""mst: design tool for multi-sensitivity soft tactile sensors."""

__version__ = "0.5.0"
