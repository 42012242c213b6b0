"""Deck cross-section of the footbridge: its composite constants and its mass per metre (SPEC 6).

The drawings (SPEC 6) give: a trapezoidal steel box girder of 16 mm plates, 470 mm deep,
"total width 2500 mm with overhangs"; a 130 mm cast-in-situ concrete slab; two closed steel
pipes 250 x 150 x 9 mm along both edges enclosing 100 mm service ducts with grouted voids;
1.4 m railings on both sides; and the fully composite section constants used by the model:
I = 0.06140 m^4 (lateral bending), 0.00439 m^4 (vertical bending), J = 0.00810 m^4.
They give no masses. Two readings of the section (``deck_section`` option of the build):

- ``"steel_overhangs"`` (default since issue 15): the girder's 16 mm top plate is 2.5 m wide
  (the box's top flange with its overhangs, as the drawing's sentence reads); the box below
  it is 1.40 m wide at the top and 0.90 m at the bottom (our assumption); the pipes stand on
  the plate's edges (150 mm wide, 250 mm high) and the slab is cast between them (2.20 m).
  Transformed to steel (n = E_steel / E_concrete = 200 / 28), this section has
  I_lat = 0.0627, I_vert = 0.00453 m^4 and (Bredt, slab in the top wall with G_c / G_s)
  J = 0.0078 m^4: the given constants within 2-4 % (:func:`composite_constants`);
- ``"slab_overhangs"`` (the estimate before issue 15, kept to reproduce the earlier model):
  the slab spans from the 1.40 m box top to the pipes, no steel overhangs. Its I_lat is
  0.0455 m^4, 26 % below the given 0.0614 m^4: this reading misses steel the source's
  section has. Its masses are :data:`LEGACY_MASS_ITEMS` (rough offsets, kept verbatim).

Mass per metre and mass moment of inertia about the deck axis (the spine at the composite
centroid): m = sum rho_i A_i, I_x = sum rho_i (A_i (y_i^2 + (z_i - z_c)^2) + I_own,i) over the
parts; line masses (railings, ducts) with their own extent. Coordinates: y across the deck,
z up from the underside of the box, metres; z_c the composite centroid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

E_STEEL_PA = 200e9
E_CONCRETE_PA = 28e9
G_STEEL_PA = 77e9
POISSON_CONCRETE = 0.2
RHO_STEEL_KG_PER_M3 = 7850.0
RHO_CONCRETE_KG_PER_M3 = 2500.0  # reinforced concrete
RHO_GROUT_KG_PER_M3 = 2300.0

#: the given (source's) fully composite constants, transformed to steel (m^4)
GIVEN_I_LATERAL_M4 = 0.06140
GIVEN_I_VERTICAL_M4 = 0.00439
GIVEN_J_M4 = 0.00810

# --- dimensions (m) ------------------------------------------------------------------
PLATE_T_M = 0.016
BOX_DEPTH_M = 0.47
BOX_TOP_WIDTH_M = 1.40  # our assumption (trapezoid widths not given)
BOX_BOTTOM_WIDTH_M = 0.90  # our assumption
DECK_WIDTH_M = 2.50
SLAB_T_M = 0.13
PIPE_WIDTH_M = 0.15
PIPE_HEIGHT_M = 0.25
PIPE_T_M = 0.009
DUCT_DIAMETER_M = 0.10
#: empty 110 mm PVC duct (3.2 mm wall), per duct: our assumption (services not given)
DUCT_KG_PER_M = 1.6
RAILING_HEIGHT_M = 1.4
#: posts, top and bottom rails and infill of a 1.4 m steel railing, per side: our assumption
RAILING_KG_PER_M = 35.0
#: share of the girder's plate steel added for diaphragms, overhang brackets and stiffeners
STEEL_ALLOWANCE = 0.10
#: surfacing on the slab: none on the drawings (the slab is the walking surface)
SURFACING_KG_PER_M2 = 0.0

SECTIONS = ("steel_overhangs", "slab_overhangs")


@dataclass(frozen=True)
class Part:
    """A piece of the cross-section (per metre of deck): area A at centroid (y, z), its own
    second moments about horizontal (i_zz) and vertical (i_yy) axes, material. Line masses
    (railings, ducts) have A = 0 and ``line_kg_per_m`` > 0 with their own r^2 in ``r2_own``."""

    item: str
    material: str  # steel, concrete, grout, line
    area_m2: float
    y_m: float
    z_m: float
    i_zz_m4: float = 0.0  # own, about the horizontal axis through the centroid (vertical bending)
    i_yy_m4: float = 0.0  # own, about the vertical axis (lateral bending)
    line_kg_per_m: float = 0.0
    r2_own_m2: float = 0.0


DENSITY = {"steel": RHO_STEEL_KG_PER_M3, "concrete": RHO_CONCRETE_KG_PER_M3, "grout": RHO_GROUT_KG_PER_M3}
#: modular ratio to steel of the structural materials (grout and line masses carry nothing)
MODULAR = {"steel": 1.0, "concrete": E_CONCRETE_PA / E_STEEL_PA}


def _rect(item, material, y0, y1, z0, z1) -> Part:
    b, h = y1 - y0, z1 - z0
    return Part(item, material, b * h, (y0 + y1) / 2, (z0 + z1) / 2, b * h**3 / 12, h * b**3 / 12)


def _hollow(item, material, y0, y1, z0, z1, t) -> list[Part]:
    """Outer rectangle minus inner one, as one part (rectangular tube of wall t)."""
    outer, inner = _rect(item, material, y0, y1, z0, z1), _rect(item, material, y0 + t, y1 - t, z0 + t, z1 - t)
    return [Part(item, material, outer.area_m2 - inner.area_m2, outer.y_m, outer.z_m,
                 outer.i_zz_m4 - inner.i_zz_m4, outer.i_yy_m4 - inner.i_yy_m4)]


def _web(item, y_bottom, y_top, depth, t) -> Part:
    """Inclined thin web from (y_bottom, 0) to (y_top, depth)."""
    length = math.hypot(y_top - y_bottom, depth)
    a = length * t
    return Part(item, "steel", a, (y_bottom + y_top) / 2, depth / 2, a * depth**2 / 12,
                a * (y_top - y_bottom) ** 2 / 12)


def section_parts(section: str = "steel_overhangs") -> list[Part]:
    """The parts of one reading of the cross-section (both sides listed)."""
    if section not in SECTIONS:
        raise ValueError(f"unknown deck section {section!r}; known: {SECTIONS}")
    t, d = PLATE_T_M, BOX_DEPTH_M
    half_top, half_bottom, half_deck = BOX_TOP_WIDTH_M / 2, BOX_BOTTOM_WIDTH_M / 2, DECK_WIDTH_M / 2
    top_half = half_deck if section == "steel_overhangs" else half_top
    parts = [_rect("steel girder", "steel", -half_bottom, half_bottom, 0.0, t),
             _rect("steel girder", "steel", -top_half, top_half, d - t, d)]
    parts += [_web("steel girder", s * half_bottom, s * half_top, d, t) for s in (-1, 1)]
    inner = half_deck - PIPE_WIDTH_M  # inner face of the pipes
    slab_top = d + SLAB_T_M
    parts.append(_rect("concrete slab", "concrete", -inner, inner, d, slab_top))
    # pipes: standing on the steel overhangs, or level with the slab's top (earlier reading)
    z0 = d if section == "steel_overhangs" else slab_top - PIPE_HEIGHT_M
    for s in (-1, 1):
        y0, y1 = sorted((s * inner, s * half_deck))
        parts += _hollow("edge pipes", "steel", y0, y1, z0, z0 + PIPE_HEIGHT_M, PIPE_T_M)
        yc, zc = (y0 + y1) / 2, z0 + PIPE_HEIGHT_M / 2
        tp = PIPE_T_M
        void = _rect("grout in pipes", "grout", y0 + tp, y1 - tp, z0 + tp, z0 + PIPE_HEIGHT_M - tp)
        duct = math.pi * DUCT_DIAMETER_M**2 / 4
        r4 = duct * DUCT_DIAMETER_M**2 / 16  # second moment of the duct's disc about a diameter
        parts.append(Part("grout in pipes", "grout", void.area_m2 - duct, yc, zc, void.i_zz_m4 - r4, void.i_yy_m4 - r4))
        parts.append(Part("service ducts", "line", 0.0, yc, zc, line_kg_per_m=DUCT_KG_PER_M,
                          r2_own_m2=DUCT_DIAMETER_M**2 / 8))
        # railings on the pipes: centroid at mid-height above the walking surface (slab top)
        parts.append(Part("railings", "line", 0.0, yc, slab_top + RAILING_HEIGHT_M / 2,
                          line_kg_per_m=RAILING_KG_PER_M, r2_own_m2=RAILING_HEIGHT_M**2 / 12))
    if SURFACING_KG_PER_M2 > 0:  # pragma: no cover - none on the drawings
        parts.append(Part("surfacing", "line", 0.0, 0.0, slab_top, line_kg_per_m=SURFACING_KG_PER_M2 * 2 * inner,
                          r2_own_m2=(2 * inner) ** 2 / 12))
    return parts


@dataclass(frozen=True)
class CompositeConstants:
    """Section constants transformed to steel: area, centroid height, I_vertical, I_lateral, J."""

    area_m2: float
    z_centroid_m: float
    i_vertical_m4: float
    i_lateral_m4: float
    j_m4: float


def composite_constants(section: str = "steel_overhangs") -> CompositeConstants:
    """Transformed (to steel) constants of the steel and concrete parts (grout carries nothing):
    A = sum n_i A_i, z_c = sum n_i A_i z_i / A, I = sum n_i (I_own + A_i d_i^2), and
    J = 4 A_0^2 / sum(s / t) (Bredt) of the closed cell bounded by the box's bottom plate, webs
    and top wall (plate plus slab, the slab as steel of thickness t_slab G_c / G_s)."""
    parts = [p for p in section_parts(section) if p.material in MODULAR]
    w = [MODULAR[p.material] for p in parts]
    area = sum(wi * p.area_m2 for wi, p in zip(w, parts))
    zc = sum(wi * p.area_m2 * p.z_m for wi, p in zip(w, parts)) / area
    i_vert = sum(wi * (p.i_zz_m4 + p.area_m2 * (p.z_m - zc) ** 2) for wi, p in zip(w, parts))
    i_lat = sum(wi * (p.i_yy_m4 + p.area_m2 * p.y_m**2) for wi, p in zip(w, parts))
    g_ratio = E_CONCRETE_PA / (2 * (1 + POISSON_CONCRETE)) / G_STEEL_PA
    t_slab = SLAB_T_M * g_ratio
    t_top = PLATE_T_M + t_slab
    z_top = ((BOX_DEPTH_M - PLATE_T_M / 2) * PLATE_T_M + (BOX_DEPTH_M + SLAB_T_M / 2) * t_slab) / t_top
    height = z_top - PLATE_T_M / 2
    web = math.hypot((BOX_TOP_WIDTH_M - BOX_BOTTOM_WIDTH_M) / 2, height)
    a0 = (BOX_TOP_WIDTH_M + BOX_BOTTOM_WIDTH_M) / 2 * height
    j = 4 * a0**2 / (BOX_BOTTOM_WIDTH_M / PLATE_T_M + 2 * web / PLATE_T_M + BOX_TOP_WIDTH_M / t_top)
    return CompositeConstants(area, zc, i_vert, i_lat, j)


def mass_items(section: str = "steel_overhangs") -> list[tuple[str, float, float]]:
    """(item, mass kg/m, mass moment of inertia about the spine kg m^2/m) per item of a
    section read from its parts; the steel allowance is distributed like the girder."""
    zc = composite_constants(section).z_centroid_m
    totals: dict[str, list[float]] = {}
    for p in section_parts(section):
        if p.material == "line":
            m, own = p.line_kg_per_m, p.line_kg_per_m * p.r2_own_m2
        else:
            rho = DENSITY[p.material]
            m, own = rho * p.area_m2, rho * (p.i_zz_m4 + p.i_yy_m4)
        ix = m * (p.y_m**2 + (p.z_m - zc) ** 2) + own
        acc = totals.setdefault(p.item, [0.0, 0.0])
        acc[0] += m
        acc[1] += ix
    girder = totals["steel girder"]
    items = [("steel girder", *girder),
             ("diaphragms, brackets, stiffeners", STEEL_ALLOWANCE * girder[0], STEEL_ALLOWANCE * girder[1])]
    items += [(name, m, ix) for name, (m, ix) in totals.items() if name != "steel girder"]
    return items


#: Deck mass estimate before issue 15 ("slab_overhangs"): (item, kg/m, y of centroid m,
#: z of centroid from the spine m, own r^2 m^2); items on both edges listed once with their
#: total mass and |y|. Steel box 1.40/0.90 m, 16 mm plates (0.0538 m^2); 10 % allowance;
#: slab 2.20 x 0.13 m; pipes 2 x 6876 mm^2; grout 2 x 22770 mm^2; railings 35 kg/m per side.
LEGACY_MASS_ITEMS = (
    ("steel box", 422.5, 0.0, -0.25, 0.20),
    ("diaphragms, stiffeners", 42.2, 0.0, -0.25, 0.20),
    ("concrete slab", 715.0, 0.0, 0.06, 2.20**2 / 12.0),
    ("edge pipes", 108.0, 1.175, 0.0, 0.005),
    ("grout in pipes", 104.8, 1.175, 0.0, 0.003),
    ("railings", 70.0, 1.25, 0.80, 0.16),
)
#: area transformed to steel of the estimate before issue 15 (box 0.0538 + pipes 0.0138 + slab / 7.14)
LEGACY_AREA_M2 = 0.108


def deck_mass_per_m(section: str = "steel_overhangs") -> tuple[float, float]:
    """Deck mass (kg/m) and mass moment of inertia about the spine (kg m^2/m) of a reading.

    ``steel_overhangs``: sums of :func:`mass_items`; ``slab_overhangs``: m = sum m_i and
    I_x = sum m_i (y_i^2 + z_i^2 + r_i^2) over :data:`LEGACY_MASS_ITEMS`.
    """
    if section == "slab_overhangs":
        m = sum(item[1] for item in LEGACY_MASS_ITEMS)
        ix = sum(item[1] * (item[2] ** 2 + item[3] ** 2 + item[4]) for item in LEGACY_MASS_ITEMS)
        return m, ix
    items = mass_items(section)
    return sum(i[1] for i in items), sum(i[2] for i in items)


def deck_area_m2(section: str = "steel_overhangs") -> float:
    """Axial area of the deck elements, transformed to steel."""
    return LEGACY_AREA_M2 if section == "slab_overhangs" else composite_constants(section).area_m2
