"""The ``mst`` command line: :mod:`mst_cli.cli.app` is the group (the console script's entry),
one module per command, :mod:`mst_cli.cli.common` for what they share."""
