"""Body and garment as DOLFINx meshes: the same mesh on 1 and 2 ranks (run with mpiexec -n 2)."""

import numpy as np
import pytest

from fenics_garment._stack import MPI, dolfinx, ufl
from fenics_garment.geometry.garments import cylinder_body, make_tube
from fenics_garment.geometry.surface import areas


def _area(mesh, tags=None, value=None):
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=tags)
    form = dolfinx.fem.form(dolfinx.fem.Constant(mesh, 1.0) * (dx(value) if tags else dx))
    return mesh.comm.allreduce(dolfinx.fem.assemble_scalar(form), op=MPI.SUM)


@pytest.mark.mpi
@pytest.mark.parametrize("quads", [False, True])
def test_tube_mesh_identical_on_any_rank_count(quads):
    comm = MPI.COMM_WORLD
    body = cylinder_body(0.1, 0.2, h=0.03)
    tube = make_tube(body, -0.07, h=0.02, quads=quads, order=1, comm=comm)
    mesh = tube.mesh
    assert mesh.topology.dim == 2 and mesh.geometry.dim == 3
    n_cells = mesh.topology.index_map(2).size_global
    assert n_cells == len(tube.cells)
    # lateral area of the tube: 2π r L with r = 0.093 (polygonal: slightly less)
    exact = 2 * np.pi * 0.093 * 0.2
    assert _area(mesh) == pytest.approx(exact, rel=5e-3)
    front = tube.panel("front")
    arrays_front = areas(tube.points, tube.triangles())[
        tube.cell_panel[tube.triangle_cell] == front
    ]
    # triangles: the same flat cells; quads: bilinear cells vs two flat triangles each
    rel = 1e-10 if not quads else 1e-3
    assert _area(mesh, tube.cell_tags, front) == pytest.approx(arrays_front.sum(), rel=rel)
    # the curved (order-2, default) mesh: edge nodes on the cylinder, the area error of the
    # polygon (−θ²/6 ≈ −0.3 % at 2 cm on r = 9.3 cm) gone to O(θ⁴)
    curved = make_tube(body, -0.07, h=0.02, quads=quads, comm=comm).mesh
    assert curved.geometry.cmaps[0].degree == 2
    assert abs(_area(curved) / exact - 1) < 0.1 * abs(_area(mesh) / exact - 1)
    hem_facets = tube.facet_tags.find(tube.edge("hem"))
    n_hem = comm.allreduce(
        int(np.sum(hem_facets < mesh.topology.index_map(1).size_local)), op=MPI.SUM
    )
    assert n_hem == len(tube.edge_nodes["hem"])
    # orientation signs make every cell normal point away from the axis
    sign = tube.cell_orientation()
    x = mesh.geometry.x
    dm = mesh.geometry.dofmaps[0]
    n = np.cross(x[dm[:, 1]] - x[dm[:, 0]], x[dm[:, 2]] - x[dm[:, 0]]) * sign[:, None]
    assert np.all(np.einsum("ij,ij->i", n[:, :2], x[dm].mean(axis=1)[:, :2]) > 0)
    # the warp as a P1 vector Function: unit and vertical on a cylinder
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (3,)))
    w = tube.warp_function(V).x.array.reshape(-1, 3)
    assert np.allclose(np.linalg.norm(w, axis=1), 1.0) and np.abs(w[:, 2]).min() > 0.999


@pytest.mark.mpi
def test_body_to_dolfinx_keeps_regions():
    comm = MPI.COMM_WORLD
    body = cylinder_body(0.1, 0.2, h=0.03)
    md = body.to_dolfinx(comm)
    assert md.mesh.topology.index_map(2).size_global == len(body.triangles)
    assert "cylinder" in md.physical_groups
    total = areas(body.vertices, body.triangles).sum()
    assert _area(md.mesh, md.cell_tags, 1) == pytest.approx(total, rel=1e-10)
