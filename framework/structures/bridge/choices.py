"""The bridge model's modelling choices as rows (item, value, origin, reason), for ``choices.csv``.

:func:`modelling_choices` takes the model's options and formats every value from the same
constants the build uses, so the table cannot drift from the model. ``origin`` is
"source-given" (a value or method stated in SPEC 6) or "our assumption" (with the reason).
"""

from __future__ import annotations

from framework.structures.bridge.build import FINAL_TOLERANCE, RIGID_FACTOR
from framework.structures.bridge.geometry import (
    ANCHOR_OFFSETS,
    BEARINGS,
    CABLE_AREA_M2,
    CABLE_MASS_KG_PER_M,
    DECK_LENGTH_M,
    DESIGN_TENSION_N,
    E_CABLE_PA,
    N_DECK_ELEMENTS,
    PYLON_BASE_Z_M,
    SENSOR_NODES,
)
from framework.structures.bridge.section import (
    BOX_BOTTOM_WIDTH_M,
    BOX_TOP_WIDTH_M,
    GIVEN_I_LATERAL_M4,
    GIVEN_I_VERTICAL_M4,
    GIVEN_J_M4,
    RAILING_KG_PER_M,
    RHO_CONCRETE_KG_PER_M3,
    RHO_GROUT_KG_PER_M3,
    STEEL_ALLOWANCE,
    composite_constants,
    deck_area_m2,
    deck_mass_per_m,
    mass_items,
)

SOURCE = "source-given"
OURS = "our assumption"


def _row(item: str, value: str, origin: str, reason: str) -> dict[str, str]:
    return {"item": item, "value": value, "origin": origin, "reason": reason}


def _section_rows(deck_section: str) -> list[dict[str, str]]:
    c = composite_constants(deck_section)
    m, ix = deck_mass_per_m(deck_section)
    given = (f"I_lat {GIVEN_I_LATERAL_M4:.5f}, I_vert {GIVEN_I_VERTICAL_M4:.5f}, J {GIVEN_J_M4:.5f} m^4")
    rows = [
        _row("deck section constants", given + ", E 200 GPa, G 77 GPa (transformed to steel)", SOURCE,
             "fully composite section of SPEC 6"),
    ]
    if deck_section == "steel_overhangs":
        rows.append(_row(
            "deck section reading",
            f"16 mm steel top plate 2.5 m wide (box top flange with overhangs); box {BOX_TOP_WIDTH_M:.2f} m top, "
            f"{BOX_BOTTOM_WIDTH_M:.2f} m bottom; pipes on the plate edges; slab between the pipes",
            OURS,
            f"'total width 2500 mm with overhangs' read as the girder's width; this section reproduces the given "
            f"constants (I_lat {c.i_lateral_m4:.4f}, I_vert {c.i_vertical_m4:.5f}, J {c.j_m4:.4f} m^4, within 4 %); "
            f"the box widths are not given"))
        for name, mass, inertia in mass_items(deck_section):
            rows.append(_row(f"deck mass: {name}", f"{mass:.1f} kg/m, {inertia:.1f} kg m^2/m about the deck axis",
                             *_mass_origin(name)))
    else:
        rows.append(_row("deck section reading", "slab spans from the 1.40 m box top to the pipes (before issue 15)",
                         OURS, f"earlier estimate; its I_lat {c.i_lateral_m4:.4f} m^4 is 26 % below the given one"))
    rows += [
        _row("deck mass", f"{m:.1f} kg/m ({m * DECK_LENGTH_M / 1000:.1f} t), lumped at the 49 spine nodes", OURS,
             "not given (SPEC 6: derive from the section); sum of the items above"),
        _row("deck mass moment of inertia", f"{ix:.1f} kg m^2/m about the deck axis (composite centroid)", OURS,
             "sum of m (y^2 + z^2) + own inertia over the items; the mass centroid's 0.08 m offset from the axis "
             "(lateral-torsional mass coupling, S^2/(m I_x) = 0.010) is neglected"),
        _row("deck axial area", f"{deck_area_m2(deck_section):.4f} m^2 (transformed to steel)", OURS,
             "from the section reading; only the axial stiffness depends on it"),
    ]
    return rows


def _mass_origin(name: str) -> tuple[str, str]:
    reasons = {
        "steel girder": (SOURCE, "16 mm plates, 470 mm deep, 2.5 m wide (SPEC 6); box widths our assumption"),
        "diaphragms, brackets, stiffeners": (OURS, f"{STEEL_ALLOWANCE:.0%} of the girder's plates, not on the "
                                             "drawings given to us"),
        "concrete slab": (SOURCE, f"130 mm slab between the pipes, {RHO_CONCRETE_KG_PER_M3:.0f} kg/m^3 "
                          "(reinforced concrete: our assumption)"),
        "edge pipes": (SOURCE, "two 250 x 150 x 9 mm steel pipes"),
        "grout in pipes": (OURS, f"the pipes' voids around the 100 mm ducts grouted (SPEC 6), "
                           f"{RHO_GROUT_KG_PER_M3:.0f} kg/m^3; mass only (not in the given constants)"),
        "service ducts": (OURS, "empty 110 mm PVC ducts, 1.6 kg/m each; services not given"),
        "railings": (OURS, f"1.4 m railings (SPEC 6) on the pipes, {RAILING_KG_PER_M:.0f} kg/m per side "
                     "(posts, rails, infill), centroid at mid-height; 8 m sections carry no load"),
    }
    return reasons.get(name, (OURS, ""))


def modelling_choices(cable_elements: int = 4, lateral_restraint: str = "rigid", tensions: str = "installed",
                      deck_section: str = "steel_overhangs", **_) -> list[dict[str, str]]:
    """Rows (item, value, origin, reason) of the bridge model built with these options."""
    abut, pylon = BEARINGS["abutment"], BEARINGS["pylon"]
    tension_items = DESIGN_TENSION_N.items()
    lateral = {
        "rigid": (f"rigid ({RIGID_FACTOR:g} x the vertical stiffness, not scaled by K_bearing)",
                  "pivot bearings at the pylon and guided sliding bearings at the abutments hold the deck in plan "
                  "(steel on steel); with this the lateral modes are within 3 % of the source's initial model "
                  "(guided: 8-12 % below it)"),
        "guided": ("the vertical stiffness of each support line, scaled by K_bearing",
                   "default before issue 15: guides as stiff as the elastomer in compression"),
        "shear": ("the elastomer's shear stiffness", "the deck sways as a rigid body at about 1.2 Hz"),
    }[lateral_restraint]
    rows = [
        _row("deck elements", f"{N_DECK_ELEMENTS} elastic beam-columns on the spine, 59.5 m, two spans", SOURCE,
             "48 deck elements (SPEC 6)"),
        *_section_rows(deck_section),
        _row("bearings", f"per support line: abutment shear {abut['shear']:.3g} N/m, vertical {abut['vertical']:.3g} "
             f"N/m, torsion {abut['torsion']:.3g} N m/rad; pylon {pylon['shear']:.3g}, {pylon['vertical']:.3g}, "
             f"{pylon['torsion']:.3g}", SOURCE,
             "SPEC 6 (K_s = A G / t longitudinal, K_v, K_rot); the pylon's K_rot = K_v (0.45 m)^2 / 4 fits two "
             "bearings 450 mm apart, the abutment's does not, used as given"),
        _row("bearing lateral restraint", lateral[0], OURS, lateral[1]),
        _row("bearing level", "at the deck axis (spine)", OURS, "a beam model; the bearings' offset below the axis "
             "(~0.42 m) is not modelled"),
        _row("cables", f"{cable_elements} corotational truss element(s) per cable, E {E_CABLE_PA / 1e9:.0f} GPa, "
             f"A {CABLE_AREA_M2 * 1e6:.0f} mm^2, {CABLE_MASS_KG_PER_M:.2f} kg/m", SOURCE,
             "4-element chains, 32 mm cables, E 165 GPa (SPEC 6); A and mass of the full 32 mm circle: "
             "our assumption (the metallic area of a strand would be ~25 % less; K_cable updates it)"),
        _row("cable anchors", "deck elements " + ", ".join(f"{g} {o}" for g, o in ANCHOR_OFFSETS.items())
             + " from the pylon, at the pipes (y = +-1.175 m)", OURS, "'about 8 m apart' (SPEC 6)"),
        _row("cable tensions", f"{tensions}: " + ", ".join(f"{g} {t / 1e3:.0f} kN" for g, t in tension_items),
             OURS, "installed (initial strain before gravity) or final dead-load tensions are not stated; "
             + ("installed: the deck weight raises them" if tensions == "installed"
                else f"final: initial strains iterated to {FINAL_TOLERANCE:.1%}")),
        _row("pylon", f"two 400WC328 legs, strong axis in the A-frame's plane, bases {-PYLON_BASE_Z_M:.1f} m below "
             "the deck, crossbeam at deck level, strut at 9.2 m", OURS, "sections and height given (SPEC 6); "
             "orientation, base level and bracing layout not given"),
        _row("analysis", "nonlinear gravity (one Newton step), then eigen analysis on the deformed state", SOURCE,
             "SPEC 6"),
        _row("mode classification", "deck modes: deck share of kinetic energy >= 0.1, type by the largest deck "
             "share (vertical, lateral, torsional); longitudinal deck modes and modes above 15 Hz dropped", OURS,
             "cable modes crowd the spectrum (SPEC 6)"),
        _row("measured shapes", f"reference shapes of the initial model at {2 * 2 * len(SENSOR_NODES)} deck DOFs "
             f"(uz and uy at both edges of {len(SENSOR_NODES)} stations)", OURS,
             "measured shapes not published (SPEC 6): the MAC term only guards mode identity"),
    ]
    return rows
