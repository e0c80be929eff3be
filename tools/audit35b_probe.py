# ruff: noqa: E501, E731
"""Round-35b bad-input probes, coverage-driven: the public names that the probe and test
files (``tools/audit*_probe.py``, ``tests/test_input_probes_*.py``, ``test_bad_input.py``,
``test_silent_answers*.py``, ``test_numerics_*.py``) name least, given bad and edge input,
and numerically hard but valid cases checked against closed forms or central differences;
with round 34b's leftovers. The table of ``tools/probe_table.py`` (probe | outcome | what
happened).

The count (``probe_table.mention_counts``, which now also reads ``test_numerics_*.py``;
``AUDIT35B_COUNT=1`` prints it): past the result containers (``FieldCurvature``,
``GeometryCheck``, ``OPDFan``…, 0-4 mentions) the least named functions were
``trace_backward`` (18), ``parameterization``/``StageArgs``/``ImageObjective`` (19),
``Objective``, the surface constructors (16-25), ``random_params``/``CatalogRegion`` (27),
``evaluate_design``, ``paraxial_data``, ``sensor_field_grid`` (28-29),
``angular_magnification``, ``reversed_lens``, ``TableMaterials`` (30); parameters never
named: ``marechal_strehl``'s ``rms_waves``, ``zernike_nm``'s ``j``, ``encircled_energy``'s
``radii``, ``radius_for_fraction``'s ``fraction``; and in ``jaxlens.imaging`` (which exports
modules only) ``otf.diffraction_mtf``, ``sampling.field_vignetting``/``field_xy``.

Gaps found and fixed:
1. ``encircled_energy``/``radius_for_fraction`` (and ``plot_encircled_energy``): a field that
   looks like radians warned under ``spot_rays``, ``chief_ray`` or ``psf`` (the inner
   analyses), once per wavelength; now once, under the function called.
2. ``plot_encircled_energy`` traced each field twice (``radius_for_fraction``, then
   ``encircled_energy``): now once (``encircled.energy_samples``, ``energy_within``,
   ``radius_holding``). Cooke triplet, default 3 fields: 6 -> 3 traces a figure; the first
   figure is compile-bound (9.6 and 9.7 s before, 8.6 and 9.5 s after, load 9 on 2 cores)
   and a warm one takes 0.2 s either way, so the saving is small.
3. ``write_exr``/``write_psf_stack``: an image whose every nonzero value is below float32's
   least magnitude (1.4e-45) was written as all 0: refused. Otherwise the values are rounded
   to float32 as any float32 store does (1e-50 beside 1 becomes 0; subnormals such as 1e-40
   are kept, no flush to zero): documented.
4. JSON lens files: numbers in quotes ("thickness": "5", fields ["0"], aperture.epd "10",
   ``{"nd": "1.62"}``) were read as numbers; the format documents only "inf" strings (and the
   ``n`` table's keys). Refused with the key path.
5. AGF ``OD`` records were skipped whatever they held: text, a comma decimal or more than 6
   values are refused with the line.
6. ``paraxial_data(...).entrance_pupil_diameter`` was the lens's weakly typed epd: it alone
   took bfloat16 from a bfloat16 operand. Now of the lens's dtype, strongly typed.
7. ``angular_magnification`` under jit: 550 (nm) gave -6.8 for the 4x telescope's -4.
8. ``marechal_strehl`` under jit: -0.1 wave gave 0.674. (``Wavefront.strehl`` stays
   unchecked: its RMS is one.)
9. ``sampling.field_vignetting``: 100°, '5' or three fields gave zeros.
10. ``otf.diffraction_mtf``: its slope at ν = 0 was half of −4/(π ν_c) (``jnp.maximum``'s tie
    rule); now the slope on ν ≥ 0.
11. ``trace_path``'s and ``trace_backward``'s ``upto``, ``newton_iters``, lens and rays were
    refused as ``trace``'s (``trace_backward("cooke", …)``: an AttributeError).

Before (branch base fd24690, an archive) and after (branch audit35b), the same probes,
``PYTHONPATH=<tree> python tools/audit35b_probe.py`` from the tree's root, 133 probes, about
2 minutes each way (2 shared cores):
    before: clear error: 70, crash: 1, ok: 34, silent wrong: 20, vague error: 8
    after:  clear error: 97, ok: 36

Probe (before -> after):
    encircled_energy field 10° in radians: warning names                   vague error  -> clear error
    radius_for_fraction field 10° in radians: warning names                vague error  -> clear error
    radius_for_fraction reference chief, radians                           vague error  -> clear error
    encircled_energy diffraction, radians                                  vague error  -> clear error
    encircled_energy field 10° (control: no warning)                       ok           -> ok
    plot_encircled_energy fields in radians: warning names                 vague error  -> clear error
    write_exr all 1e-50 (below float32's least)                            silent wrong -> clear error
    write_exr [1, 1e-50] (control: float32 rounding)                       ok           -> ok
    write_exr 1e-40 (control: float32 subnormal kept)                      ok           -> ok
    write_psf_stack all 1e-50                                              silent wrong -> clear error
    json "thickness": "5"                                                  silent wrong -> clear error
    json "radius": "22.01359"                                              silent wrong -> clear error
    json "conic": "-1"                                                     silent wrong -> clear error
    json fields values ["0", "14", "20"]                                   silent wrong -> clear error
    json wavelengths_nm as strings                                         silent wrong -> clear error
    json aperture.epd "10"                                                 silent wrong -> clear error
    json material {"nd": "1.62", "vd": 60}                                 silent wrong -> clear error
    json primary_wavelength_nm "587.5618"                                  silent wrong -> clear error
    json semi_diameter "inf" (control: documented)                         ok           -> ok
    json refcase file with n tables (control)                              ok           -> ok
    agf OD with text (OD 1.0 x 0 1 1 1)                                    silent wrong -> clear error
    agf OD with a comma decimal                                            silent wrong -> clear error
    agf OD with 8 values (LD's merged in)                                  silent wrong -> clear error
    agf OD -1 ×6 (control)                                                 ok           -> ok
    paraxial_data fields promote alike (bfloat16 × EPD)                    silent wrong -> ok
    angular_magnification wavelength 550 (nm)                              clear error  -> clear error
    angular_magnification of a focal lens (control: defined for any lens)  ok           -> ok
    angular_magnification wavelength NaN                                   clear error  -> clear error
    angular_magnification wavelength [0.5, 0.6] (each as alone?)           ok           -> ok
    angular_magnification wavelength '0.55'                                clear error  -> clear error
    angular_magnification jit wavelength 550                               silent wrong -> clear error
    angular_magnification integer wavelength 1 (control)                   ok           -> ok
    reversed_lens image_distance NaN                                       clear error  -> clear error
    reversed_lens image_distance -1e9 (control: any real mm)               ok           -> ok
    reversed_lens image_distance '5'                                       clear error  -> clear error
    paraxial_data wavelength 587.56 (nm)                                   clear error  -> clear error
    paraxial_data wavelength [0.5, 0.6]                                    clear error  -> clear error
    paraxial_data wavelength 0 (empty-ish)                                 clear error  -> clear error
    paraxial_data jit wavelength 587.56                                    clear error  -> clear error
    paraxial_data integer wavelength 1 (control: N-BK7 singlet)            ok           -> ok
    entrance_pupil_magnification wavelength 550                            clear error  -> clear error
    x_section of a non-lens                                                clear error  -> clear error
    sensor_field_grid n=0                                                  clear error  -> clear error
    sensor_field_grid n=2.5                                                clear error  -> clear error
    sensor_field_grid n=True                                               clear error  -> clear error
    sensor_field_grid n=10**6                                              clear error  -> clear error
    evaluate_design n=0                                                    clear error  -> clear error
    evaluate_design min_valid 1.5                                          clear error  -> clear error
    evaluate_design min_valid NaN                                          clear error  -> clear error
    random_params dtype int32                                              clear error  -> clear error
    random_params key 0 (an int)                                           clear error  -> clear error
    trace_backward upto 99                                                 clear error  -> clear error
    trace_backward upto -1                                                 clear error  -> clear error
    trace_backward newton_iters -1                                         vague error  -> clear error
    trace_backward rays of another dtype (float64 on float32 lens)         ok           -> ok
    marechal_strehl -0.1                                                   clear error  -> clear error
    marechal_strehl NaN (control: documented, no rays)                     ok           -> ok
    marechal_strehl '0.1'                                                  clear error  -> clear error
    marechal_strehl jit -0.1                                               silent wrong -> clear error
    marechal_strehl [] (control: empty)                                    ok           -> ok
    zernike_nm 0 (noll)                                                    clear error  -> clear error
    zernike_nm 2.5                                                         clear error  -> clear error
    zernike_nm True                                                        clear error  -> clear error
    zernike_terms terms 0                                                  clear error  -> clear error
    zernike_terms x [3] y [4]                                              clear error  -> clear error
    zernike_terms x NaN (control: NaN propagates)                          ok           -> ok
    encircled_energy radii []                                              clear error  -> clear error
    encircled_energy radii [-0.01]                                         clear error  -> clear error
    encircled_energy radii 20 (control: under 2 diagonals, a radius)       ok           -> ok
    encircled_energy radii 100 (µm as mm)                                  clear error  -> clear error
    encircled_energy jit radii [-0.01]                                     clear error  -> clear error
    encircled_energy integer radii [0, 1] (control)                        ok           -> ok
    radius_for_fraction 0                                                  clear error  -> clear error
    radius_for_fraction 1                                                  clear error  -> clear error
    radius_for_fraction 80 (percent)                                       clear error  -> clear error
    radius_for_fraction jit 1.5                                            clear error  -> clear error
    radius_for_fraction fields [0, 10] (several)                           clear error  -> clear error
    self_intersection n_radial 0                                           clear error  -> clear error
    self_intersection semi_diameters of 2 for 6                            clear error  -> clear error
    self_intersection min_gap NaN                                          clear error  -> clear error
    sine_path n 0 (control: one stage at the end)                          ok           -> ok
    sine_path start NaN                                                    clear error  -> clear error
    reweighting_mask threshold 1.5                                         clear error  -> clear error
    reweighting_mask rms NaN                                               clear error  -> clear error
    field_vignetting field 100°                                            silent wrong -> clear error
    linear_to_srgb NaN                                                     clear error  -> clear error
    read_psf_stack a PNG                                                   clear error  -> clear error
    read_psf_stack a folder                                                clear error  -> clear error
    write_psf_stack [3, 3] (no stack axis)                                 clear error  -> clear error
    srgb_to_linear 1.5 (control: refused, encoded values are in [0, 1])    clear error  -> clear error
    field_vignetting field '5'                                             silent wrong -> clear error
    field_vignetting fields [0, 10, 20] (three)                            silent wrong -> clear error
    trace_path upto 99                                                     vague error  -> clear error
    trace_path upto 2.5                                                    vague error  -> clear error
    trace_backward lens 'cooke'                                            crash        -> clear error
    trace_path uniform 'yes'                                               clear error  -> clear error
    trace_path [0] rays (control: empty)                                   ok           -> ok
    Aperture half_x 0                                                      clear error  -> clear error
    Aperture shape 'square'                                                clear error  -> clear error
    Aperture half_y NaN                                                    clear error  -> clear error
    Aperture blocks 1 (int)                                                clear error  -> clear error
    TiltedPlane tan_x inf                                                  clear error  -> clear error
    TiltedPlane tan_x 45 (degrees?)                                        clear error  -> clear error
    Biconic kx NaN                                                         clear error  -> clear error
    Biconic cx '0.02'                                                      clear error  -> clear error
    OddAsphere coeffs [[1, 2]]                                             clear error  -> clear error
    XYPolynomial norm_radius 0                                             clear error  -> clear error
    Stop semi_diameter -1                                                  clear error  -> clear error
    Plane semi_diameter 0                                                  clear error  -> clear error
    Sensor resolution (0, 10)                                              clear error  -> clear error
    Sensor resolution (10.5, 10)                                           clear error  -> clear error
    Tabulated wavelengths in nm                                            clear error  -> clear error
    Tabulated decreasing wavelengths (control: sorted, same index)         ok           -> ok
    Tabulated indices [1.5] for 3 wavelengths                              clear error  -> clear error
    field_xy [[1, 2, 3]] (control: a [1, 3] batch of θy)                   ok           -> ok
    efl wavelength [] (empty)                                              clear error  -> clear error
    rms_spot fields [] (empty)                                             clear error  -> clear error
    rms_spot fields float32 on a float64 lens (control)                    ok           -> ok
    rms_spot fields int [0, 10] (control)                                  ok           -> ok
    efl jit wavelength 587.56 (nm)                                         clear error  -> clear error
    bfl wavelength -0.5                                                    clear error  -> clear error
    efl thick singlet vs lensmaker (float64, n 1.5 Vd 1e9)                 ok           -> ok
    grad efl at a flat surface (c = 0) vs FD                               ok           -> ok
    grad efl wrt EPD is 0                                                  ok           -> ok
    grad rms_spot wrt field on axis                                        ok           -> ok
    marechal_strehl value and gradient vs closed form                      ok           -> ok
    zernike_terms d/dx at the origin (closed form)                         ok           -> ok
    zernike_terms d/dx at the rim (closed form)                            ok           -> ok
    diffraction_mtf at νc/2 and gradients at 0, νc                         silent wrong -> ok
    sRGB curve continuous at the knee, round trip                          ok           -> ok
    angular_magnification of the 4× Kepler                                 ok           -> ok
    encircled energy at radius 0, D50 gradient finite                      ok           -> ok
    grad rms_spot wrt EPD vs FD (rim rays)                                 ok           -> ok
"""

import json
import math
import os
import pathlib
import sys
import warnings

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
warnings.simplefilter("ignore")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from probe_table import COOKE, ROOT, checked, fresh, jitted, mention_counts, probe, run, warned  # noqa: E402

import jaxlens as jl  # noqa: E402
import jaxlens.analysis as A  # noqa: E402
import jaxlens.design as D  # noqa: E402

KEPLER = os.path.join(ROOT, "tests", "data", "afocal_kepler.zmx")
R10, R20 = math.radians(10), math.radians(20)


def count_mentions(top=60):
    """The exported names named least in every probe and test file (this round's left out)."""
    mention_counts(lambda f: "35b" in f, top)


# ----------------------------------------------------------------------- round 34b's leftovers
def leftovers():
    lens = jl.zoo.cooke_triplet()
    probe(
        "encircled_energy field 10° in radians: warning names",
        warned(lambda: A.encircled_energy(lens, R10, jnp.array([0.01]))),
        "encircled_energy:",
        "radians",
    )
    probe(
        "radius_for_fraction field 10° in radians: warning names",
        warned(lambda: A.radius_for_fraction(lens, R10, 0.8)),
        "radius_for_fraction:",
        "radians",
    )
    probe(
        "radius_for_fraction reference chief, radians",
        warned(lambda: A.radius_for_fraction(lens, R10, 0.8, reference="chief")),
        "radius_for_fraction:",
        "radians",
    )
    probe(
        "encircled_energy diffraction, radians",
        warned(
            lambda: A.encircled_energy(
                lens,
                R10,
                jnp.array([0.01]),
                method="diffraction",
                pixel_size=0.002,
                kernel_size=15,
                pupil_side=16,
            )
        ),
        "encircled_energy:",
        "radians",
    )
    probe(
        "encircled_energy field 10° (control: no warning)",
        warned(lambda: A.encircled_energy(lens, 10.0, jnp.array([0.01])).energy),
        good=True,
    )

    from jaxlens import plot

    probe(
        "plot_encircled_energy fields in radians: warning names",
        warned(lambda: plot.plot_encircled_energy(lens, [0.0, R10, R20])),
        "plot_encircled_energy:",
        "radians",
    )

    from jaxlens.io import images as IM

    d = fresh("exr")
    p = os.path.join(d, "a.exr")
    probe(
        "write_exr all 1e-50 (below float32's least)",
        lambda: (IM.write_exr(p, np.full((2, 2), 1e-50)), IM.read_exr(p))[1],
        "float32",
        "1e-50",
    )
    probe(
        "write_exr [1, 1e-50] (control: float32 rounding)",
        lambda: (IM.write_exr(p, np.array([[1.0, 1e-50]])), IM.read_exr(p))[1],
        good=True,
    )
    probe(
        "write_exr 1e-40 (control: float32 subnormal kept)",
        lambda: (IM.write_exr(p, np.full((2, 2), 1e-40)), float(IM.read_exr(p)[0, 0]))[1],
        good=True,
    )
    probe(
        "write_psf_stack all 1e-50",
        lambda: IM.write_psf_stack(os.path.join(d, "s.exr"), np.full((1, 3, 3), 1e-50)),
        "float32",
        "1e-50",
    )

    base = json.loads(pathlib.Path(COOKE).read_text())

    def lf(edit):
        dd = json.loads(json.dumps(base))
        edit(dd)
        q = os.path.join(fresh("l"), "lens.json")
        pathlib.Path(q).write_text(json.dumps(dd))
        return lambda: f"efl {float(jl.efl(jl.load(q))):.6g}"

    probe(
        'json "thickness": "5"',
        lf(lambda d: d["surfaces"][1].update(thickness="5")),
        "surface 1: thickness",
        "'5'",
    )
    probe(
        'json "radius": "22.01359"',
        lf(lambda d: d["surfaces"][1].update(radius="22.01359")),
        "surface 1: radius",
        "'22.01359'",
    )
    probe(
        'json "conic": "-1"',
        lf(lambda d: d["surfaces"][1].update(conic="-1")),
        "surface 1: conic",
        "'-1'",
    )
    probe(
        'json fields values ["0", "14", "20"]',
        lf(lambda d: d["fields"].update(values=["0", "14", "20"])),
        "fields",
        "'0'",
    )
    probe(
        "json wavelengths_nm as strings",
        lf(lambda d: d.update(wavelengths_nm=["486.1327", "587.5618", "656.2725"])),
        "wavelengths_nm",
        "'486.1327'",
    )
    probe(
        'json aperture.epd "10"',
        lf(lambda d: d.update(aperture={"epd": "10"})),
        "aperture.epd",
        "'10'",
    )
    probe(
        'json material {"nd": "1.62", "vd": 60}',
        lf(lambda d: d["surfaces"][1].update(material={"nd": "1.62", "vd": 60})),
        "nd",
        "'1.62'",
    )
    probe(
        'json primary_wavelength_nm "587.5618"',
        lf(lambda d: d.update(primary_wavelength_nm="587.5618")),
        "primary_wavelength_nm",
        "'587.5618'",
    )
    probe(
        'json semi_diameter "inf" (control: documented)',
        lf(lambda d: d["surfaces"][1].update(semi_diameter="inf")),
        good=True,
    )
    probe(
        "json refcase file with n tables (control)",
        lambda: (
            f"efl {float(jl.efl(jl.load(os.path.join(ROOT, 'tests', 'refcases', 'cooke_triplet.json')))):.6g}"
        ),
        good=True,
    )

    from jaxlens.optics import agf

    def agf_text(od):
        return (
            "CC test\nNM G1 2 0 1.5168 64.17 0 0 0\n"
            "CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653 0 0 0 0\n"
            f"TD 0 0 0 0 0 0 20\n{od}\nLD 0.3 2.5\n"
        )

    probe(
        "agf OD with text (OD 1.0 x 0 1 1 1)",
        lambda: len(agf.parse_agf(agf_text("OD 1.0 x 0 1 1 1"), "t.agf")),
        "t.agf:5",
        "OD",
    )
    probe(
        "agf OD with a comma decimal",
        lambda: len(agf.parse_agf(agf_text("OD 1,2 1 0 1 1 1"), "t.agf")),
        "t.agf:5",
        "OD",
    )
    probe(
        "agf OD with 8 values (LD's merged in)",
        lambda: len(agf.parse_agf(agf_text("OD -1 -1 -1 -1 -1 -1 0.3 2.5"), "t.agf")),
        "t.agf:5",
        "OD",
        "6",
    )
    probe(
        "agf OD -1 ×6 (control)",
        lambda: len(agf.parse_agf(agf_text("OD -1 -1 -1 -1 -1 -1"), "t.agf")),
        good=True,
    )

    def weak():
        pd = jl.paraxial_data(lens)
        x = jnp.ones(2, jnp.bfloat16)
        got = {
            k: str((x * getattr(pd, k)).dtype)
            for k in ("efl", "entrance_pupil_diameter", "exit_pupil_diameter")
        }
        return len(set(got.values())) == 1, f"bfloat16 × each field: {got}"

    checked("paraxial_data fields promote alike (bfloat16 × EPD)", weak)


# ---------------------------------------------------------------- least-named public functions
def least_named():
    lens = jl.zoo.cooke_triplet()
    kep = jl.load(KEPLER)
    probe(
        "angular_magnification wavelength 550 (nm)",
        lambda: A.angular_magnification(kep, 550.0),
        "wavelength",
        "µm",
    )
    probe(
        "angular_magnification of a focal lens (control: defined for any lens)",
        lambda: A.angular_magnification(lens),
        good=True,
    )
    probe(
        "angular_magnification wavelength NaN",
        lambda: A.angular_magnification(kep, float("nan")),
        "wavelength",
    )
    checked(
        "angular_magnification wavelength [0.5, 0.6] (each as alone?)",
        lambda: (
            bool(
                np.allclose(
                    A.angular_magnification(kep, jnp.array([0.5, 0.6])),
                    [A.angular_magnification(kep, 0.5), A.angular_magnification(kep, 0.6)],
                    rtol=1e-12,
                )
            ),
            str(A.angular_magnification(kep, jnp.array([0.5, 0.6]))),
        ),
    )
    probe(
        "angular_magnification wavelength '0.55'",
        lambda: A.angular_magnification(kep, "0.55"),
        "wavelength",
    )
    probe(
        "angular_magnification jit wavelength 550",
        jitted(lambda w: A.angular_magnification(kep, w), jnp.asarray(550.0)),
        "wavelength",
    )
    probe(
        "angular_magnification integer wavelength 1 (control)",
        lambda: A.angular_magnification(kep, 1),
        good=True,
    )
    from jaxlens.tracing import reversed_lens

    probe(
        "reversed_lens image_distance NaN",
        lambda: reversed_lens(lens, image_distance=float("nan")).num_surfaces,
        "image_distance",
    )
    probe(
        "reversed_lens image_distance -1e9 (control: any real mm)",
        lambda: reversed_lens(lens, image_distance=-1e9).num_surfaces,
        good=True,
    )
    probe(
        "reversed_lens image_distance '5'",
        lambda: reversed_lens(lens, image_distance="5").num_surfaces,
        "image_distance",
    )
    probe(
        "paraxial_data wavelength 587.56 (nm)",
        lambda: jl.paraxial_data(lens, 587.56).efl,
        "wavelength",
        "µm",
    )
    probe(
        "paraxial_data wavelength [0.5, 0.6]",
        lambda: jl.paraxial_data(lens, jnp.array([0.5, 0.6])).efl,
        "wavelength",
    )
    probe(
        "paraxial_data wavelength 0 (empty-ish)",
        lambda: jl.paraxial_data(lens, 0.0).efl,
        "wavelength",
    )
    probe(
        "paraxial_data jit wavelength 587.56",
        jitted(lambda w: jl.paraxial_data(lens, w).efl, jnp.asarray(587.56)),
        "wavelength",
    )
    bk7 = jl.Lens(
        surfaces=(jl.Sphere(1 / 30.0), jl.Sphere(-1 / 45.0)),
        thickness=jnp.array([6.0, 33.4]),
        materials=(jl.get_material("N-BK7"), jl.Air()),
        epd=10.0,
        fields=jnp.array([0.0, 10.0]),
    )
    probe(
        "paraxial_data integer wavelength 1 (control: N-BK7 singlet)",
        lambda: jl.paraxial_data(bk7, 1).efl,
        good=True,
    )
    probe(
        "entrance_pupil_magnification wavelength 550",
        lambda: jl.paraxial.entrance_pupil_magnification(lens, 550.0),
        "wavelength",
        "µm",
    )
    probe("x_section of a non-lens", lambda: jl.paraxial.x_section("lens"), "lens")
    spec = D.DesignSpec()
    probe("sensor_field_grid n=0", lambda: D.sensor_field_grid(spec, 0), "n")
    probe("sensor_field_grid n=2.5", lambda: D.sensor_field_grid(spec, 2.5), "n")
    probe("sensor_field_grid n=True", lambda: D.sensor_field_grid(spec, True), "n")
    probe("sensor_field_grid n=10**6", lambda: D.sensor_field_grid(spec, 10**6)[0].shape, "n")
    probe("evaluate_design n=0", lambda: D.evaluate_design(lens, spec, n=0), "n")
    probe(
        "evaluate_design min_valid 1.5",
        lambda: D.evaluate_design(lens, spec, min_valid=1.5),
        "min_valid",
    )
    probe(
        "evaluate_design min_valid NaN",
        lambda: D.evaluate_design(lens, spec, min_valid=float("nan")),
        "min_valid",
    )
    probe(
        "random_params dtype int32",
        lambda: D.random_params(spec, jax.random.PRNGKey(0), jnp.int32),
        "dtype",
    )
    probe("random_params key 0 (an int)", lambda: D.random_params(spec, 0), "key")
    rays = jl.sampling.collimated(lens, 0.0, jl.sampling.pupil_grid(5))
    out = jl.trace(lens, rays)
    probe("trace_backward upto 99", lambda: jl.trace_backward(lens, out, upto=99).origin, "upto")
    probe("trace_backward upto -1", lambda: jl.trace_backward(lens, out, upto=-1).origin, "upto")
    probe(
        "trace_backward newton_iters -1",
        lambda: jl.trace_backward(lens, out, newton_iters=-1).origin,
        "trace_backward:",
        "newton_iters",
    )
    probe(
        "trace_backward rays of another dtype (float64 on float32 lens)",
        lambda: (
            jl.trace_backward(
                lens,
                jax.tree_util.tree_map(
                    lambda a: a.astype(jnp.float64) if a.dtype == jnp.float32 else a, out
                ),
            ).origin.dtype
        ),
        good=True,
    )
    probe("marechal_strehl -0.1", lambda: A.marechal_strehl(-0.1), "rms_waves")
    probe(
        "marechal_strehl NaN (control: documented, no rays)",
        lambda: A.marechal_strehl(float("nan")),
        good=True,
    )
    probe("marechal_strehl '0.1'", lambda: A.marechal_strehl("0.1"), "rms_waves")
    probe("marechal_strehl jit -0.1", jitted(A.marechal_strehl, jnp.asarray(-0.1)), "rms_waves")
    probe(
        "marechal_strehl [] (control: empty)",
        lambda: A.marechal_strehl(jnp.zeros((0,))).shape,
        good=True,
    )
    probe("zernike_nm 0 (noll)", lambda: A.zernike_nm(0), "j")
    probe("zernike_nm 2.5", lambda: A.zernike_nm(2.5), "j")
    probe("zernike_nm True", lambda: A.zernike_nm(True), "j")
    probe(
        "zernike_terms terms 0",
        lambda: A.zernike_terms(jnp.zeros(3), jnp.zeros(3), terms=0),
        "terms",
    )
    probe(
        "zernike_terms x [3] y [4]", lambda: A.zernike_terms(jnp.zeros(3), jnp.zeros(4)), "x", "y"
    )
    probe(
        "zernike_terms x NaN (control: NaN propagates)",
        lambda: A.zernike_terms(jnp.array([jnp.nan]), jnp.zeros(1), terms=3),
        good=True,
    )
    probe(
        "encircled_energy radii []", lambda: A.encircled_energy(lens, 0.0, jnp.zeros((0,))), "radii"
    )
    probe(
        "encircled_energy radii [-0.01]",
        lambda: A.encircled_energy(lens, 0.0, jnp.array([-0.01])),
        "radii",
    )
    probe(
        "encircled_energy radii 20 (control: under 2 diagonals, a radius)",
        lambda: A.encircled_energy(lens, 0.0, 20.0).energy,
        good=True,
    )
    probe(
        "encircled_energy radii 100 (µm as mm)", lambda: A.encircled_energy(lens, 0.0, 100.0), "µm"
    )
    probe(
        "encircled_energy jit radii [-0.01]",
        jitted(lambda r: A.encircled_energy(lens, 0.0, r).energy, jnp.array([-0.01])),
        "radii",
    )
    probe(
        "encircled_energy integer radii [0, 1] (control)",
        lambda: A.encircled_energy(lens, 0.0, jnp.array([0, 1])).energy,
        good=True,
    )
    probe("radius_for_fraction 0", lambda: A.radius_for_fraction(lens, 0.0, 0.0), "fraction")
    probe("radius_for_fraction 1", lambda: A.radius_for_fraction(lens, 0.0, 1), "fraction")
    probe(
        "radius_for_fraction 80 (percent)", lambda: A.radius_for_fraction(lens, 0.0, 80), "fraction"
    )
    probe(
        "radius_for_fraction jit 1.5",
        jitted(lambda f: A.radius_for_fraction(lens, 0.0, f), jnp.asarray(1.5)),
        "fraction",
    )
    probe(
        "radius_for_fraction fields [0, 10] (several)",
        lambda: A.radius_for_fraction(lens, jnp.array([0.0, 10.0, 20.0]), 0.8),
        "field",
    )
    probe("self_intersection n_radial 0", lambda: A.self_intersection(lens, n_radial=0), "n_radial")
    probe(
        "self_intersection semi_diameters of 2 for 6",
        lambda: A.self_intersection(lens, jnp.ones(2)),
        "semi_diameters",
    )
    probe(
        "self_intersection min_gap NaN",
        lambda: A.self_intersection(lens, min_gap=float("nan")),
        "min_gap",
    )
    probe(
        "sine_path n 0 (control: one stage at the end)", lambda: D.sine_path(0.0, 1.0, 0), good=True
    )
    probe("sine_path start NaN", lambda: D.sine_path(float("nan"), 1.0, 5), "start")
    probe(
        "reweighting_mask threshold 1.5",
        lambda: D.reweighting_mask(jnp.ones((3, 4)), threshold=1.5),
        "threshold",
    )
    probe(
        "reweighting_mask rms NaN", lambda: D.reweighting_mask(jnp.array([[1.0, jnp.nan]])), "rms"
    )
    probe("field_vignetting field 100°", lambda: jl.sampling.field_vignetting(lens, 100.0), "field")
    from jaxlens.io import images as IM

    probe("linear_to_srgb NaN", lambda: IM.linear_to_srgb(np.array([np.nan])), "NaN")
    png = os.path.join(fresh("p"), "x.png")
    probe(
        "read_psf_stack a PNG",
        lambda: (IM.write_png(png, np.ones((2, 2))), IM.read_psf_stack(png))[1],
        "exr",
    )
    probe(
        "read_psf_stack a folder",
        lambda: IM.read_psf_stack(os.path.dirname(png)),
        "read_psf_stack",
        "not a file",
    )
    probe(
        "write_psf_stack [3, 3] (no stack axis)",
        lambda: IM.write_psf_stack(os.path.join(fresh("p"), "s.exr"), np.ones((3, 3))),
        "psfs",
    )
    probe(
        "srgb_to_linear 1.5 (control: refused, encoded values are in [0, 1])",
        lambda: IM.srgb_to_linear(np.array([1.5])),
        "[0, 1]",
    )
    probe("field_vignetting field '5'", lambda: jl.sampling.field_vignetting(lens, "5"), "field")
    probe(
        "field_vignetting fields [0, 10, 20] (three)",
        lambda: jl.sampling.field_vignetting(lens, jnp.array([0.0, 10.0, 20.0])),
        "field",
        "shape",
    )


# ------------------------------------------------------- more of the least named, mixed types
def more():
    lens = jl.zoo.cooke_triplet()
    rays = jl.sampling.collimated(lens, 0.0, jl.sampling.pupil_grid(5))
    probe(
        "trace_path upto 99",
        lambda: jl.trace_path(lens, rays, upto=99).origin,
        "trace_path:",
        "upto",
    )
    probe(
        "trace_path upto 2.5",
        lambda: jl.trace_path(lens, rays, upto=2.5).origin,
        "trace_path:",
        "upto",
    )
    probe(
        "trace_backward lens 'cooke'",
        lambda: jl.trace_backward("cooke", rays),
        "trace_backward:",
        "lens",
    )
    probe(
        "trace_path uniform 'yes'",
        lambda: jl.trace_path(lens, rays, uniform="yes").origin,
        "uniform",
    )
    none = jax.tree_util.tree_map(lambda a: a[:0] if jnp.ndim(a) else a, rays)
    probe(
        "trace_path [0] rays (control: empty)",
        lambda: jl.trace_path(lens, none).origin.shape,
        good=True,
    )
    probe("Aperture half_x 0", lambda: jl.Aperture("rect", 0.0, 1.0), "half_x")
    probe("Aperture shape 'square'", lambda: jl.Aperture("square", 1.0, 1.0), "shape")
    probe("Aperture half_y NaN", lambda: jl.Aperture("ellipse", 1.0, float("nan")), "half_y")
    probe("Aperture blocks 1 (int)", lambda: jl.Aperture("circle", 1.0, 1.0, blocks=1), "blocks")
    probe("TiltedPlane tan_x inf", lambda: jl.TiltedPlane(tan_x=float("inf")), "tan_x")
    probe("TiltedPlane tan_x 45 (degrees?)", warned(lambda: jl.TiltedPlane(tan_x=45.0)), "tan_x")
    probe("Biconic kx NaN", lambda: jl.Biconic(c=0.01, cx=0.02, kx=float("nan")), "kx")
    probe("Biconic cx '0.02'", lambda: jl.Biconic(c=0.01, cx="0.02"), "cx")
    probe(
        "OddAsphere coeffs [[1, 2]]", lambda: jl.OddAsphere(c=0.01, coeffs=[[1e-4, 2e-6]]), "coeffs"
    )
    probe(
        "XYPolynomial norm_radius 0",
        lambda: jl.XYPolynomial(c=0.01, coeffs=(1e-3,), norm_radius=0.0),
        "norm_radius",
    )
    probe("Stop semi_diameter -1", lambda: jl.Stop(-1.0), "semi_diameter")
    probe("Plane semi_diameter 0", lambda: jl.Plane(0.0), "semi_diameter")
    probe("Sensor resolution (0, 10)", lambda: jl.Sensor((0, 10), 0.005), "resolution")
    probe("Sensor resolution (10.5, 10)", lambda: jl.Sensor((10.5, 10), 0.005), "resolution")
    probe(
        "Tabulated wavelengths in nm",
        lambda: jl.Tabulated(jnp.array([486.0, 587.0, 656.0]), jnp.array([1.52, 1.517, 1.515])),
        "µm",
    )
    probe(
        "Tabulated decreasing wavelengths (control: sorted, same index)",
        lambda: float(
            jl.Tabulated(jnp.array([0.656, 0.587, 0.486]), jnp.array([1.515, 1.517, 1.52])).index(
                0.5
            )
        ),
        good=True,
    )
    probe(
        "Tabulated indices [1.5] for 3 wavelengths",
        lambda: jl.Tabulated(jnp.array([0.486, 0.587, 0.656]), jnp.array([1.5])),
        "indices",
    )
    probe(
        "field_xy [[1, 2, 3]] (control: a [1, 3] batch of θy)",
        lambda: jl.sampling.field_xy(jnp.array([[1.0, 2.0, 3.0]])).shape,
        good=True,
    )
    probe("efl wavelength [] (empty)", lambda: jl.efl(lens, jnp.zeros((0,))), "wavelength")
    probe("rms_spot fields [] (empty)", lambda: A.rms_spot(lens, fields=jnp.zeros((0,))), "fields")
    probe(
        "rms_spot fields float32 on a float64 lens (control)",
        lambda: (
            A.rms_spot(
                lens.astype(jnp.float64), fields=jnp.array([0.0, 10.0], jnp.float32)
            ).polychromatic.dtype
        ),
        good=True,
    )
    probe(
        "rms_spot fields int [0, 10] (control)",
        lambda: A.rms_spot(lens, fields=jnp.array([0, 10])).polychromatic,
        good=True,
    )
    probe(
        "efl jit wavelength 587.56 (nm)",
        jitted(lambda w: jl.efl(lens, w), jnp.asarray(587.56)),
        "wavelength",
    )
    probe("bfl wavelength -0.5", lambda: jl.bfl(lens, -0.5), "wavelength")


# -------------------------------------------------------- numerically hard but valid cases
def fd(f, x, h):
    return (f(x + h) - f(x - h)) / (2 * h)


def numerics():
    lens64 = jl.zoo.cooke_triplet().astype(jnp.float64)

    def singlet(c2=-1 / 45.0, epd=10.0):
        return jl.Lens(
            surfaces=(jl.Sphere(1 / 30.0), jl.Sphere(c2)),
            thickness=jnp.array([6.0, 33.4]),
            materials=(jl.ModelGlass(1.5, 1e9), jl.Air()),
            epd=epd,
            fields=jnp.array([0.0, 10.0]),
        ).astype(jnp.float64)

    def thick():
        n, c1, c2, t = 1.5, 1 / 30.0, -1 / 45.0, 6.0
        phi = (n - 1) * (c1 - c2) + (n - 1) ** 2 * t * c1 * c2 / n
        got = float(jl.efl(singlet()))
        return abs(got - 1 / phi) < 1e-9 * (1 / phi), f"efl {got:.12g}, lensmaker {1 / phi:.12g}"

    checked("efl thick singlet vs lensmaker (float64, n 1.5 Vd 1e9)", thick)

    def flat():
        g = float(jax.grad(lambda c: jl.efl(singlet(c)))(0.0))
        f = float(fd(lambda c: jl.efl(singlet(c)), 0.0, 1e-6))
        return abs(g - f) < 1e-6 * abs(
            f
        ), f"d efl/d c2 at c2 = 0 (flat): grad {g:.10g}, central FD {f:.10g}"

    checked("grad efl at a flat surface (c = 0) vs FD", flat)

    def epd():
        g = float(jax.grad(lambda e: jl.efl(singlet(epd=e)))(10.0))
        return g == 0.0, f"d efl/d epd {g:g} (0: paraxial)"

    checked("grad efl wrt EPD is 0", epd)

    def on_axis():
        def spot(f):
            return A.rms_spot(lens64, fields=jnp.stack([f])).polychromatic[0]

        g = float(jax.grad(spot)(0.0))
        return math.isfinite(g) and abs(g) < 1e-8, f"d rms/d field at 0° {g:.3g} (0 by symmetry)"

    checked("grad rms_spot wrt field on axis", on_axis)

    def strehl():
        s = 0.1
        got, g = float(A.marechal_strehl(s)), float(jax.grad(A.marechal_strehl)(s))
        want = math.exp(-((2 * math.pi * s) ** 2))
        g0 = float(jax.grad(A.marechal_strehl)(0.0))
        ok = (
            abs(got - want) < 1e-12
            and abs(g - (-2 * (2 * math.pi) ** 2 * s * want)) < 1e-9
            and g0 == 0.0
        )
        return ok, f"S(0.1) {got:.12g} (exp form {want:.12g}), dS/dσ {g:.8g}, at 0 {g0:g}"

    checked("marechal_strehl value and gradient vs closed form", strehl)

    def zern_origin():
        def z(x):
            return A.zernike_terms(x, jnp.zeros(()), terms=4)

        j = np.asarray(jax.jacfwd(z)(0.0))
        want = np.array([0.0, 2.0, 0.0, 0.0])  # Noll: Z1 1, Z2 2ρcosθ = 2x, Z3 2y, Z4 √3(2ρ²−1)
        return bool(
            np.allclose(j, want, atol=1e-12)
        ), f"dZ1..4/dx at the origin {j.round(12).tolist()} (want {want.tolist()})"

    checked("zernike_terms d/dx at the origin (closed form)", zern_origin)

    def zern_rim():
        def z(x):
            return A.zernike_terms(x, jnp.zeros(()), terms=4)[3]

        g, f = float(jax.grad(z)(1.0)), float(fd(z, 1.0, 1e-6))
        return abs(g - 4 * math.sqrt(3)) < 1e-9 and abs(
            f - g
        ) < 1e-6, f"dZ4/dx at the rim {g:.12g} (4√3 {4 * math.sqrt(3):.12g}), FD {f:.10g}"

    checked("zernike_terms d/dx at the rim (closed form)", zern_rim)

    from jaxlens.imaging import otf

    def mtf_half():
        lam, fn = 0.5e-3, 4.0
        cut = 1 / (lam * fn)
        got = float(otf.diffraction_mtf(jnp.asarray(cut / 2), lam, fn))
        want = 2 / math.pi * (math.acos(0.5) - 0.5 * math.sqrt(0.75))
        g0 = float(jax.grad(lambda v: otf.diffraction_mtf(v, lam, fn))(0.0))
        gc = float(jax.grad(lambda v: otf.diffraction_mtf(v, lam, fn))(cut))
        return (
            abs(got - want) < 1e-12 and abs(g0 - (-4 / math.pi / cut)) < 1e-9 and math.isfinite(gc),
            f"MTF(νc/2) {got:.12g} ({want:.12g}); dMTF/dν at 0 {g0:.6g} (−4/(π νc) {-4 / math.pi / cut:.6g}), at νc {gc:g}",
        )

    checked("diffraction_mtf at νc/2 and gradients at 0, νc", mtf_half)

    from jaxlens.io import images as IM

    def srgb():
        t = 0.0031308
        lo, hi = (
            float(IM.linear_to_srgb(np.array(t - 1e-12))),
            float(IM.linear_to_srgb(np.array(t + 1e-12))),
        )
        x = np.linspace(0, 1, 101)
        rt = np.max(np.abs(IM.srgb_to_linear(IM.linear_to_srgb(x)) - x))
        return abs(
            lo - hi
        ) < 1e-6 and rt < 1e-12, f"sRGB at the knee {lo:.9f} / {hi:.9f}; round trip {rt:.2g}"

    checked("sRGB curve continuous at the knee, round trip", srgb)

    def kepler():
        kep = jl.load(KEPLER)
        m = float(A.angular_magnification(kep))
        return abs(abs(m) - 4.0) < 0.05, f"angular magnification {m:.6g} (a 4× Kepler telescope)"

    checked("angular_magnification of the 4× Kepler", kepler)

    def ee_grad():
        def e(r):
            return A.encircled_energy(lens64, 0.0, jnp.stack([r])).energy[0]

        g = jax.grad(lambda L: A.radius_for_fraction(L, 0.0, 0.5))(lens64)
        leaves = [
            np.asarray(x)
            for x in jax.tree_util.tree_leaves(g)
            if hasattr(x, "dtype") and jnp.issubdtype(x.dtype, jnp.floating)
        ]
        fin = all(np.all(np.isfinite(x)) for x in leaves)
        return fin and float(
            e(0.0)
        ) == 0.0, f"EE(0) {float(e(0.0)):g}; grad of D50 radius wrt the lens finite: {fin}"

    checked("encircled energy at radius 0, D50 gradient finite", ee_grad)

    def stop_rim():
        def spot(e):
            return A.rms_spot(singlet(epd=e), fields=jnp.array([0.0])).polychromatic[0]

        g, f = float(jax.grad(spot)(10.0)), float(fd(spot, 10.0, 1e-5))
        return abs(g - f) < 1e-5 * abs(f) + 1e-12, f"d rms/d EPD {g:.10g}, central FD {f:.10g}"

    checked("grad rms_spot wrt EPD vs FD (rim rays)", stop_rim)


if __name__ == "__main__":
    if os.environ.get("AUDIT35B_COUNT"):
        count_mentions()
    run([leftovers, least_named, more, numerics])
