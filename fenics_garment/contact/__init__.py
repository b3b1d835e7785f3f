"""Contact of the garment with the body surface: search, gap, UFL terms, Uzawa loop, pressure.

Modules:
    search: closest point on the body triangles, robust sign, smoothed normals, broad phase.
    primitives: analytic test bodies (sphere, cylinder) as triangle meshes.
    state: the contact points on the garment and their gap/normal Functions (``refresh``).
    terms: UFL expressions of the normal penalty / augmented Lagrangian / friction terms.
    uzawa: the augmented-Lagrangian loop.
    pressure: contact pressure on the garment and its transfer to the body surface.
"""
