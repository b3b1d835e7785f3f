"""Scenes: a TOML file describing body, garment, physics and dressing, and the run that follows.

``config`` (load + validate), ``build`` (body, garment, shell model, contact), ``dressing``
(shrink the body back to its size in adaptive steps), ``run`` (the whole pipeline with outputs).
"""
