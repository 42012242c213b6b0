"""Geometry and full mode shapes of a model: nodes, elements, node displacements, sensor points.

:func:`model_shapes(model, theta, structure)` returns a :class:`ModelShapes`: the model's
modes at ``theta`` (``model.modal``, the modes the objective sees) with, for each, the
displacement (u_x, u_y, u_z) of every node, and the sensor points at which measured shapes
are drawn. How a model's geometry is found:

- an :class:`~framework.models.opensees.OpenSeesModel` (any user's model, the detailed lab
  frame, the beam) or a model wrapping one as ``.plain`` (the bridge's fast path): the model
  is built in the OpenSees domain and read back (``getNodeTags``, ``nodeCoord``,
  ``getEleTags``, ``eleNodes``); the eigenproblem of the built domain is solved with the
  framework's scipy solver and each mode of ``model.modal(theta)`` is matched to the domain
  mode of nearest frequency, signed and scaled to agree at the measured DOFs. Element groups
  come from what the build function returned: keys or attributes named ``<group>_elements``
  and ``<group>_nodes`` (the bridge's ``deck_nodes``, ``pylon_nodes``, ``cable_elements``);
- the beam's numpy model: its OpenSees twin (same matrices);
- the 3-DOF lab frame: the rigid slab (0.65 m square) on four 0.7 m columns, the slab moved
  by (x, y, theta), theta = torsion / (b/2);
- a shear building (``floor1`` .. DOFs): floors stacked one storey apart;
- anything else (e.g. the SMU footbridge, whose data hold no coordinates): no geometry,
  the shapes are shown channel by channel.

Measured DOFs become sensor points: a translational DOF at its node with its direction; the
lab frame's (y, x, torsion) move the four slab corners rigidly. A measured shape s (at the
DOFs) moves point p by sum_d T[p, :, d] s_d.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from framework.models.base import full_theta

log = logging.getLogger(__name__)

#: lab frame: slab width and column length (SPEC 5, the detailed model's drawings), m
SLAB_WIDTH_M = 0.65
STOREY_HEIGHT_M = 0.7
LAB_FRAME_DOFS = ("y", "x", "torsion")


@dataclass
class ModelShapes:
    """Modes of a model at one point with their geometry.

    frequencies_hz (n,), dof_shapes (n_dof, n) at ``dofs`` (as ``model.modal`` gives them),
    mode_types (n,) or None; node_tags (N,), coords (N, 3) in m (or the model's length unit),
    node_shapes (N, 3, n) scaled like dof_shapes; elements: list of (tag, node tags, group);
    points: sensor point names, point_coords (P, 3), T (P, 3, n_dof). ``coords`` is None
    when the model has no geometry.
    """

    frequencies_hz: np.ndarray
    dof_shapes: np.ndarray
    dofs: tuple[str, ...]
    mode_types: np.ndarray | None = None
    node_tags: np.ndarray | None = None
    coords: np.ndarray | None = None
    node_shapes: np.ndarray | None = None
    elements: list[tuple[int, tuple[int, ...], str]] = field(default_factory=list)
    node_groups: dict[int, str] = field(default_factory=dict)
    points: list[str] = field(default_factory=list)
    point_coords: np.ndarray | None = None
    T: np.ndarray | None = None
    length_unit: str = "m"

    @property
    def has_geometry(self) -> bool:
        return self.coords is not None


def model_shapes(model, theta: Mapping[str, float], structure: str = "") -> ModelShapes:
    """The modes of ``model`` at ``theta`` with geometry where it can be found (module docstring)."""
    from framework.models.opensees import OpenSeesModel

    result = model.modal(dict(theta))
    types = result.mode_info.get("mode_type") if result.mode_info else None
    base = ModelShapes(result.frequencies_hz, result.shapes, result.dofs,
                       None if types is None else np.asarray(types, dtype=object))
    twin = _opensees_twin(model)
    try:
        if isinstance(model, OpenSeesModel) or twin is not None:
            shapes = _opensees_geometry(twin or model, theta, base)
        elif tuple(result.dofs) == LAB_FRAME_DOFS:
            shapes = _lab_frame_geometry(base)
        elif result.dofs and all(d.startswith("floor") and d[5:].isdigit() for d in result.dofs) \
                and "eigenvectors" in result.meta:
            shapes = _shear_building_geometry(base, np.asarray(result.meta["eigenvectors"], float), result)
        else:
            return base
    except Exception as exc:  # a drawing aid must not lose the study: fall back to channels
        log.warning("geometry of %s not available (%s: %s); shapes shown by channel", structure or model,
                    type(exc).__name__, exc)
        return base
    if tuple(result.dofs) == LAB_FRAME_DOFS and shapes.coords is not None:
        _rigid_slab_points(shapes, float(np.max(shapes.coords[:, 2])))
    return shapes


def _opensees_twin(model):
    """The OpenSeesModel behind a model that wraps one (bridge fast path, beam numpy model)."""
    from framework.models.opensees import OpenSeesModel

    plain = getattr(model, "plain", None)
    if isinstance(plain, OpenSeesModel):
        return plain
    if type(model).__name__ == "BeamNumpyModel":
        from framework.structures.beam.model import make_opensees_model

        p = model.parameters
        return make_opensees_model(len(p), int(getattr(model, "n_modes", 7)), float(p.lower[0]), float(p.upper[0]))
    return None


# ---- OpenSees domain -----------------------------------------------------------------------
def _opensees_geometry(model, theta: Mapping[str, float], base: ModelShapes) -> ModelShapes:
    """Build ``model`` at theta, solve the built domain and read nodes, elements and node shapes."""
    from framework.models.eigen_solve import lowest_modes
    from framework.models.opensees import ops_module, run_static
    from framework.models.opensees_matrices import DofMap, stiffness_and_mass

    ops = ops_module()
    values = dict(model.fixed)
    values.update(full_theta(model.parameters, theta))
    try:
        info, constraints = model._build_domain(ops, values)
        if model.gravity is not None:
            run_static(ops, model.gravity)
        K, M = stiffness_and_mass(ops)
        dof_map = DofMap(ops, constraints)
        n = min(max(model.n_modes, base.frequencies_hz.size), K.shape[0])
        omega2, phi = lowest_modes(K, M, n)
        tags = np.array(sorted(int(t) for t in ops.getNodeTags()))
        coords = np.zeros((tags.size, 3))
        U = np.full((tags.size, 3, omega2.size), np.nan)
        for i, tag in enumerate(tags):
            c = list(ops.nodeCoord(int(tag)))
            coords[i, : len(c)] = c[:3]
            rows = dof_map.node_rows(int(tag))
            if rows is None:
                continue
            for d in range(min(len(c), 3, len(rows))):
                U[i, d] = rows[d].of(phi)
            U[i, len(c):] = 0.0
        scale = {label: float(model.dof_scale.get(label, 1.0)) for label in model.measured_dofs}
        sensor = np.array([dof_map.row(node, direction).of(phi) * scale[label]
                           for label, (node, direction) in model.measured_dofs.items()]).reshape(-1, omega2.size)
        elements = [(int(e), tuple(int(v) for v in ops.eleNodes(int(e)))) for e in ops.getEleTags()]
    finally:
        ops.wipe()
    node_groups, element_groups = _groups(info)
    f_domain = np.sqrt(np.maximum(omega2, 0.0)) / (2 * math.pi)
    base.node_tags, base.coords = tags, _spread_degenerate(coords, tags)
    if base.coords is not coords:
        base.length_unit = "node index (the model has no coordinates)"
    base.node_shapes = _align(base, f_domain, sensor, U)
    base.elements = [(e, nodes, element_groups.get(e) or _group_of(nodes, node_groups)) for e, nodes in elements]
    base.node_groups = node_groups
    index = {int(t): i for i, t in enumerate(tags)}
    pts, pc, T = [], [], []
    for d, (label, (node, direction)) in enumerate(model.measured_dofs.items()):
        if direction > 3 or node not in index:
            continue
        name = f"node{node}"
        if name not in pts:
            pts.append(name)
            pc.append(base.coords[index[node]])
            T.append(np.zeros((3, len(base.dofs))))
        T[pts.index(name)][direction - 1, d] += 1.0 / scale[label]
    base.points, base.point_coords = pts, np.array(pc).reshape(-1, 3)
    base.T = np.array(T).reshape(len(pts), 3, len(base.dofs))
    return base


def _spread_degenerate(coords: np.ndarray, tags: np.ndarray) -> np.ndarray:
    """A model whose nodes all share one position (e.g. a 1-D chain of springs) gets its nodes
    placed one unit apart along z in tag order, so that its shapes can still be drawn."""
    if tags.size > 1 and np.ptp(coords, axis=0).max() == 0.0:
        out = coords.copy()
        out[:, 2] = np.arange(tags.size, dtype=float)
        return out
    return coords


def _align(base: ModelShapes, f_domain: np.ndarray, sensor: np.ndarray, U: np.ndarray) -> np.ndarray:
    """Node shapes (N, 3, n) of the model's modes: each mode of ``base`` takes the domain mode
    of nearest frequency, scaled by g = (s_d . s_m) / (s_d . s_d) so that its values at the
    measured DOFs s_d equal the model's s_m in the least-squares sense."""
    out = np.full((U.shape[0], 3, base.frequencies_hz.size), np.nan)
    for j, f in enumerate(base.frequencies_hz):
        k = int(np.argmin(np.abs(f_domain - f)))
        if abs(f_domain[k] - f) > 1e-4 * max(f, 1e-12):
            log.warning("mode %d (%.4g Hz): nearest mode of the built domain is %.4g Hz", j + 1, f, f_domain[k])
        sd, sm = sensor[:, k], base.dof_shapes[:, j]
        g = float(sd @ sm) / float(sd @ sd) if float(sd @ sd) > 0 else 1.0
        out[:, :, j] = U[:, :, k] * g
    return out


def _members(value) -> list[int]:
    out: list[int] = []
    stack = [value]
    while stack:
        v = stack.pop()
        if isinstance(v, dict):
            stack.extend(v.values())
        elif isinstance(v, (list, tuple, set)):
            stack.extend(v)
        elif isinstance(v, (int, np.integer)) and not isinstance(v, bool):
            out.append(int(v))
    return out


def _groups(info) -> tuple[dict[int, str], dict[int, str]]:
    """{node: group}, {element: group} from keys/attributes ``<group>_nodes``/``<group>_elements``."""
    items = info.items() if isinstance(info, dict) else (vars(info).items() if hasattr(info, "__dict__") else ())
    nodes, elements = {}, {}
    for key, value in items:
        if not isinstance(key, str) or not isinstance(value, (list, tuple, set, dict)):
            continue  # a count such as n_elements is not a group
        if key.endswith("_elements"):
            for e in _members(value):
                elements.setdefault(e, key.removesuffix("_elements"))
        elif key.endswith("_nodes"):
            for n in _members(value):
                nodes.setdefault(n, key.removesuffix("_nodes"))
    return nodes, elements


def _group_of(nodes: tuple[int, ...], node_groups: dict[int, str]) -> str:
    groups = {node_groups.get(n) for n in nodes} - {None}
    if len(groups) == 1:
        return groups.pop()
    return "structure" if not groups else "connection"


# ---- built-in models without a domain -----------------------------------------------------
def _corners(z: float) -> np.ndarray:
    h = SLAB_WIDTH_M / 2
    return np.array([[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]])


def _rigid_slab_points(shapes: ModelShapes, z: float) -> None:
    """Sensor points of the lab frame's (y, x, torsion) DOFs: the slab corners, moved rigidly
    by u_x = x - theta y_c, u_y = y + theta x_c with theta = torsion / (b/2)."""
    corners = _corners(z)
    index = {d: i for i, d in enumerate(shapes.dofs)}
    T = np.zeros((4, 3, len(shapes.dofs)))
    half = SLAB_WIDTH_M / 2
    for p, (xc, yc, _) in enumerate(corners):
        T[p, 0, index["x"]] = 1.0
        T[p, 1, index["y"]] = 1.0
        T[p, 0, index["torsion"]] = -yc / half
        T[p, 1, index["torsion"]] = xc / half
    shapes.points = ["corner SW", "corner SE", "corner NE", "corner NW"]
    shapes.point_coords, shapes.T = corners, T


def _lab_frame_geometry(base: ModelShapes) -> ModelShapes:
    """Rigid slab at 0.7 m on four columns; node shapes from the slab's rigid motion."""
    _rigid_slab_points(base, STOREY_HEIGHT_M)
    top, ground = _corners(STOREY_HEIGHT_M), _corners(0.0)
    base.node_tags = np.arange(1, 9)
    base.coords = np.vstack([ground, top])
    slab = np.einsum("pcd,dm->pcm", base.T, base.dof_shapes)
    base.node_shapes = np.concatenate([np.zeros_like(slab), slab], axis=0)
    base.elements = [(i + 1, (i + 1, i + 5), "column") for i in range(4)]
    base.elements += [(5 + i, (5 + i, 5 + (i + 1) % 4), "slab") for i in range(4)]
    base.node_groups = {i: ("ground" if i <= 4 else "slab") for i in range(1, 9)}
    return base


def _shear_building_geometry(base: ModelShapes, phi_full: np.ndarray, result) -> ModelShapes:
    """Floors stacked one storey apart (z in storeys), moving in x; the ground at z = 0."""
    n = phi_full.shape[0]
    base.length_unit = "storey"
    base.node_tags = np.arange(0, n + 1)
    base.coords = np.zeros((n + 1, 3))
    base.coords[:, 2] = np.arange(n + 1)
    U = np.zeros((n + 1, 3, phi_full.shape[1]))
    U[1:, 0, :] = phi_full
    base.node_shapes = U[:, :, : base.frequencies_hz.size]
    base.elements = [(i, (i - 1, i), "storey") for i in range(1, n + 1)]
    floors = [int(d[5:]) for d in base.dofs]
    base.points = [f"floor {f}" for f in floors]
    base.point_coords = base.coords[floors]
    base.T = np.zeros((len(floors), 3, len(floors)))
    for p in range(len(floors)):
        base.T[p, 0, p] = 1.0
    return base
