"""How the lab frame's modes are drawn: a rigid slab on four columns, sensors at its corners.

The measured DOFs (y, x, torsion) are the slab's rigid motion: the four slab corners move
by u_x = x - theta y_c, u_y = y + theta x_c with theta = torsion / (b/2). The 3-DOF model
draws the slab (0.65 m square) at 0.7 m on four columns from that motion
(:meth:`~framework.structures.lab_frame.model.ThreeDofFrame.geometry`); the detailed
OpenSees model is read from its built domain and gets the same corner sensor points
(:func:`detailed_geometry`, the hook of its descriptor).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from framework.models.geometry import ModelShapes, domain_shapes

#: slab width b and column length (SPEC 5, the detailed model's drawings), m
SLAB_WIDTH_M = 0.65
STOREY_HEIGHT_M = 0.7
CORNER_NAMES = ("corner SW", "corner SE", "corner NE", "corner NW")


def corners(z: float) -> np.ndarray:
    """The slab corners (SW, SE, NE, NW) at height z."""
    h = SLAB_WIDTH_M / 2
    return np.array([[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]])


def rigid_slab_points(shapes: ModelShapes, z: float) -> ModelShapes:
    """Sensor points of the (y, x, torsion) DOFs: the slab corners at z, moved rigidly
    by u_x = x - theta y_c, u_y = y + theta x_c with theta = torsion / (b/2)."""
    points = corners(z)
    index = {d: i for i, d in enumerate(shapes.dofs)}
    T = np.zeros((4, 3, len(shapes.dofs)))
    half = SLAB_WIDTH_M / 2
    for p, (xc, yc, _) in enumerate(points):
        T[p, 0, index["x"]] = 1.0
        T[p, 1, index["y"]] = 1.0
        T[p, 0, index["torsion"]] = -yc / half
        T[p, 1, index["torsion"]] = xc / half
    shapes.points = list(CORNER_NAMES)
    shapes.point_coords, shapes.T = points, T
    return shapes


def slab_on_columns(shapes: ModelShapes) -> ModelShapes:
    """The 3-DOF frame: rigid slab at 0.7 m on four columns; node shapes from the slab's rigid motion."""
    rigid_slab_points(shapes, STOREY_HEIGHT_M)
    top, ground = corners(STOREY_HEIGHT_M), corners(0.0)
    shapes.node_tags = np.arange(1, 9)
    shapes.coords = np.vstack([ground, top])
    slab = np.einsum("pcd,dm->pcm", shapes.T, shapes.dof_shapes)
    shapes.node_shapes = np.concatenate([np.zeros_like(slab), slab], axis=0)
    shapes.elements = [(i + 1, (i + 1, i + 5), "column") for i in range(4)]
    shapes.elements += [(5 + i, (5 + i, 5 + (i + 1) % 4), "slab") for i in range(4)]
    shapes.node_groups = {i: ("ground" if i <= 4 else "slab") for i in range(1, 9)}
    return shapes


def detailed_geometry(model, theta: Mapping[str, float], shapes: ModelShapes) -> ModelShapes:
    """The detailed model: nodes, elements and node shapes of its built OpenSees domain, sensor
    points at the slab corners (at the height of its highest node)."""
    shapes = domain_shapes(model, theta, shapes)
    return rigid_slab_points(shapes, float(np.max(shapes.coords[:, 2])))
