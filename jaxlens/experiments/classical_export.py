"""The lens a classical run exports (``python -m jaxlens.experiments.classical``): its clear
apertures, with a margin another tool's glass data cannot eat, and the notes that say how the
run evaluated it (``Lens.description``: NOTE lines of lens.zmx, "description" of lens.json).

Clear apertures. Every surface but an entrance-pupil stop gets the largest height of the
evaluation's rays that pass the lens (the n × n sensor grid of fields, the 21 × 21 pupil grid,
the pupil rim, the spec's three wavelengths), times ``1 + CLEAR_APERTURE_MARGIN``.

Measured (round 36d; every glass's index moved by ±1e-5 and by ±1e-3, all alike or
alternating): a clear semi-diameter moves by up to 1.0 × the index change (relative) on a
SCHOTT/CDGM smoke design, 2.9 × on a smoke design with the stop behind one element, and on
experiments/classical/designs/seed_1.zmx by up to 10.6 × at 1e-5 and 5.5 × at 1e-3 (its
surface 11, 3.5 mm). Re-read by optiland 0.6.3 with its own glass data (CDGM H-F51 2e-6 from
jaxlens's; the plastics far more: E48R's nd 6e-4 from Zemax's ZEON data, which jaxlens uses,
and OKP4, which optiland lacks, a model glass from the GLAS line's nd, Vd, 2.8e-4 off at F and
C), rim rays went past the former margin of 1e-9: 20 of the CDGM smoke design's 16 167
grid and axis rays, 16 of seed_1's and 40 of seed_19's. With 1e-3 they still lost 12 and
36; with 1e-2 none (nor the CDGM design). The margin, 1e-2 (at most 37 µm on these lenses),
holds index differences up to about 1.5e-3 on the most sensitive surface measured, and left the
geometry check of seed_1, seed_5 and seed_19 as it was (the same smallest gap). The NOTE
lines give jaxlens's indices, which another tool's glass data may not reproduce. Ray aiming
is not covered: the run aims at the paraxial entrance pupil (Zemax's ray aiming "Off",
optiland's default "paraxial"), as the notes say. With the stop in front (the default spec)
real aiming traces the same rays; behind an element it moved a clear semi-diameter by 12 %.

The stop in front of every element (``stop == 0``) is the entrance pupil: its semi-diameter
is EPD/2 (to 1e-9, the rim rays' rounding), which a tool that floats the aperture by stop
size reads as the file's ENPD. A stop behind elements is sized as any other surface (EPD/2
is a size in the entrance pupil's space, not the stop's: it clipped rays of a stop whose
front group magnifies the pupil).

A margin that would make the evaluation's geometry check (``analysis.self_intersection``
over the clear apertures: no overlap, every sag defined) fail where the exact heights pass it
is cut tenfold until it passes, down to none.
"""

from __future__ import annotations

import functools

CLEAR_APERTURE_MARGIN = 1e-2
"""Relative margin of an exported clear semi-diameter over the largest evaluated ray height
(every surface but an entrance-pupil stop); the module doc says how it was chosen."""

STOP_ROUNDING = 1e-9
"""Relative margin of an entrance-pupil stop's EPD/2 (its rim rays cross at EPD/2 to rounding)."""


def evaluation_notes(spec, grid: int = 16, margin: float = CLEAR_APERTURE_MARGIN) -> str:
    """The lines that lens.zmx (NOTE) and lens.json ("description") carry: how the run that
    wrote them evaluated the design (on a ``grid`` × ``grid`` field grid), so that another
    tool's re-evaluation matches."""
    h, w = spec.sensor_size
    return "\n".join(
        [
            "jaxlens classical run: summary.json's numbers are of this file, evaluated as follows.",
            f"Fields: a {grid} x {grid} grid over the {w:.10g} x {h:.10g} mm sensor "
            f"(linspace(-1, 1, {grid}) per side; summary.json best.field_angles_deg), "
            f"(thetax, thetay) with tan = sensor position / {spec.focal_length:.10g} "
            "mm; the YFLN fields here are the design fields along y (the largest, half the "
            "diagonal FoV, lies beyond the sensor's y edge: its chief ray only is evaluated).",
            "Rays: aimed at the paraxial entrance pupil (ray aiming off); 21 x 21 square pupil "
            f"grid inside the unit circle (317 rays), WAVM 1..{len(spec.wavelengths)} weighted "
            "equally; RMS = radius "
            "about the centroid of all wavelengths' rays pooled.",
            "Image surface: the sensor, at the last DISZ (no refocus); EFL, F/# = EFL/ENPD and "
            "BFL paraxial at the primary wavelength (PWAV).",
            f"Distortion: 100 (h - EFL tan theta)/(EFL tan theta) %, h the real chief ray's y at "
            f"thetay = {spec.half_fov:.10g} deg.",
            f"Apertures: CLAP = largest passing evaluated ray height x (1 + {margin:g}) (the stop "
            f"in front: ENPD/2); valid = no surface overlap over them and >= 99 % of each "
            f"field's rays reach the sensor at every WAVM (vignetting: the smallest fraction "
            f"over the wavelengths).",
        ]
    )


def with_clear_apertures(lens, spec, margin: float = CLEAR_APERTURE_MARGIN):
    """The lens (float64) with every surface's semi-diameter set to its clear aperture (module
    doc): the largest passing evaluated ray height × (1 + margin), EPD/2 at a stop in front."""
    import equinox as eqx
    import jax.numpy as jnp

    from jaxlens import analysis
    from jaxlens.design.evaluate import sensor_field_grid
    from jaxlens.imaging.sampling import pupil_grid
    from jaxlens.optics import checks

    checks.number(
        margin,
        "margin",
        "with_clear_apertures",
        lo=0,
        hi=0.1,
        unit="(relative to the largest ray height)",
    )
    lens = lens.astype(jnp.float64)
    # Leaves of an explicit dtype: weak-typed ones (from Python floats) would make every
    # jitted analysis of this lens compile a second program.
    f64 = functools.partial(jnp.asarray, dtype=jnp.float64)
    free = tuple(eqx.tree_at(lambda x: x.semi_diameter, s, f64(jnp.inf)) for s in lens.surfaces)
    lens = eqx.tree_at(lambda x: (x.surfaces, x.epd), lens, (free, f64(spec.epd)))
    lens = eqx.tree_at(lambda x: x.wavelengths, lens, f64(spec.wavelengths))
    angles, _ = sensor_field_grid(spec)
    sd = analysis.clear_semi_diameters(lens, jnp.asarray(angles), pupil=pupil_grid(21, jnp.float64))

    def sized(m):
        surfaces = tuple(
            eqx.tree_at(
                lambda x: x.semi_diameter,
                s,
                f64(
                    0.5 * spec.epd * (1 + STOP_ROUNDING)
                    if j == lens.stop == 0
                    else float(sd[j]) * (1 + m)
                ),
            )
            for j, s in enumerate(lens.surfaces)
        )
        return eqx.tree_at(lambda x: x.surfaces, lens, surfaces)

    out = sized(margin)
    if margin == 0 or bool(analysis.self_intersection(out).ok):
        return out
    exact = sized(0.0)
    if not bool(analysis.self_intersection(exact).ok):
        return out  # the exact heights fail the check too: the margin changes no verdict
    m = margin / 10
    while m >= 1e-6 * margin:
        out = sized(m)
        if bool(analysis.self_intersection(out).ok):
            return out
        m /= 10
    return exact
