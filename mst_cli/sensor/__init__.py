"""The sensor's own concepts, between the physics and the tools that use it.

document (a design or spec file as one Document) and its sections (each key declared once),
as_printed (what a printer does to a drawing: the part whose physics is simulated). Depends on
the model and on io's file plumbing; design, calibrate, cad and simulation build on it.
"""
