"""Geometry and full mode shapes of a model: nodes, elements, node displacements, sensor points.

:func:`model_shapes(model, theta, structure, geometry)` returns a :class:`ModelShapes`: the
model's modes at ``theta`` (``model.modal``, the modes the objective sees) with, for each, the
displacement (u_x, u_y, u_z) of every node, and the sensor points at which measured shapes
are drawn. Nothing here knows a structure: the geometry comes, in this order, from

1. the ``geometry`` hook given by the caller (a structure descriptor's, e.g. the detailed lab
   frame's: its domain with sensor points at the slab corners);
2. the model's own method ``geometry(theta, shapes)`` (e.g. the 3-DOF lab frame draws a
   rigid slab, a shear building stacked floors, the beam's numpy model and the bridge's fast
   path return their OpenSees twin);
3. an :class:`~framework.models.opensees.OpenSeesModel` (any user's model): its built domain;
4. else none: the shapes are shown channel by channel (e.g. the SMU footbridge, whose data
   hold no coordinates).

A hook ``geometry(model, theta, shapes)`` or method ``geometry(theta, shapes)`` gets the
:class:`ModelShapes` of the modes (no geometry yet) and returns it with the geometry filled
in, or an OpenSeesModel to read from its built domain (:func:`domain_shapes`), or None.

The built domain (:func:`domain_shapes`): the model is built in the OpenSees domain and read
back (``getNodeTags``, ``nodeCoord``, ``getEleTags``, ``eleNodes``); the eigenproblem of the
built domain is solved with the framework's scipy solver and each mode of
``model.modal(theta)`` is matched to the domain mode of nearest frequency, signed and scaled
to agree at the measured DOFs. Element groups come from what the build function returned:
keys or attributes named ``<group>_elements`` and ``<group>_nodes`` (the bridge's
``deck_nodes``, ``pylon_nodes``, ``cable_elements``). Its measured translational DOFs become
sensor points at their nodes with their directions. A measured shape s (at the DOFs) moves
point p by sum_d T[p, :, d] s_d.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from framework.models.base import full_theta

log = logging.getLogger(__name__)


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


#: ``geometry(model, theta, shapes) -> ModelShapes | OpenSeesModel | None`` (module docstring)
GeometryHook = Callable[[Any, Mapping[str, float], ModelShapes], Any]


def model_shapes(model, theta: Mapping[str, float], structure: str = "", geometry: GeometryHook | None = None
                 ) -> ModelShapes:
    """The modes of ``model`` at ``theta`` with geometry where it can be found (module docstring)."""
    from framework.models.opensees import OpenSeesModel

    result = model.modal(dict(theta))
    types = result.mode_info.get("mode_type") if result.mode_info else None
    base = ModelShapes(result.frequencies_hz, result.shapes, result.dofs,
                       None if types is None else np.asarray(types, dtype=object))
    own = getattr(model, "geometry", None)
    try:
        if geometry is not None:
            source = geometry(model, theta, base)
        elif callable(own):
            source = own(theta, base)
        else:
            source = model
        if isinstance(source, OpenSeesModel):
            return domain_shapes(source, theta, base)
        if isinstance(source, ModelShapes) and source.has_geometry:
            return source
    except Exception as exc:  # a drawing aid must not lose the study: fall back to channels
        log.warning("geometry of %s not available (%s: %s); shapes shown by channel", structure or model,
                    type(exc).__name__, exc)
    return ModelShapes(result.frequencies_hz, result.shapes, result.dofs, base.mode_types)


# ---- OpenSees domain -----------------------------------------------------------------------
def domain_shapes(model, theta: Mapping[str, float], base: ModelShapes) -> ModelShapes:
    """``base`` with the geometry of the OpenSeesModel ``model`` built at theta: nodes, elements,
    node shapes of the built domain's modes matched to ``base``'s, sensor points (module docstring)."""
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
