"""CAD of the printable sensor (build123d): parts, the fused body, the STEP assembly, mesh files.

Import the submodules directly (``mst_cli.cad.assembly``, ``.parts``, ``.mesh_io``); this
package itself imports nothing heavy, and :mod:`.manifest` (export.json) needs no CAD library.
"""
