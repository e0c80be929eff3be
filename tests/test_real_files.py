"""Issue 12 (real lens files): clipping apertures and the image medium in written .zmx files,
real ray aiming through clipping apertures, the image-space focal length, and the reader's
apertures, field types and vignetting factors."""

import dataclasses
import warnings

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import json_round_trip

import jaxlens as jl
from jaxlens.analysis import report
from jaxlens.io import zmx
from jaxlens.optics.lens import unclipped

DATA = jl.__file__.rsplit("/", 1)[0] + "/data/lenses"


def _clip_front(lens, radius, count):
    """The lens with its first ``count`` surfaces clipped at ``radius`` (mm)."""
    surfaces = tuple(
        eqx.tree_at(lambda s: s.semi_diameter, s, jnp.asarray(radius)) if i < count else s
        for i, s in enumerate(lens.surfaces)
    )
    return eqx.tree_at(lambda m: m.surfaces, lens, surfaces)


@pytest.mark.slow  # 27 s (CI time; test_ray_aiming checks the real aim's stop points in CI)
def test_real_aiming_through_clipping_apertures():
    """Aimed rays cross the stop at pupil·(stop radius) even where the front apertures clip
    the paraxial launch points; the apertures then decide which rays pass.

    Before the aiming traced the unclipped lens, two of these rays were reported valid while
    crossing the stop up to 0.66 mm from their pupil point.
    """
    clip = 16.0
    lens = _clip_front(jl.load(f"{DATA}/double_gauss.json"), clip, 2)
    pupil = jl.sampling.pupil_hexapolar(3)
    target = np.asarray(pupil * jl.paraxial_data(lens).stop_semi_diameter)
    for field in (14.0, 20.0):
        rays = jl.sampling.collimated(lens, field, pupil, aim="real")
        free = jl.trace_path(unclipped(lens), rays)
        np.testing.assert_allclose(
            np.asarray(free.origin[lens.stop, :, :2]), target, rtol=0, atol=1e-9
        )
        # Known answer for validity: the aimed ray passes iff it stays inside both apertures.
        radius = np.linalg.norm(np.asarray(free.origin[:2, :, :2]), axis=-1).max(0)
        passes = (radius <= clip) & np.asarray(free.valid[-1])
        valid = np.asarray(jl.trace(lens, rays).valid)
        np.testing.assert_array_equal(valid, passes)
        assert 0 < passes.sum() < passes.size  # the apertures clip some rays, not all


def test_efl_in_air_and_in_image_space_for_a_singlet_into_glass():
    """A thick singlet whose image space is glass (n′ = 1.6): 1/Φ and n′/Φ from the
    thick-lens power Φ = Φ1 + Φ2 − (t/n)·Φ1·Φ2."""
    n, n_img, c1, c2, t = 1.5, 1.6, 1 / 40.0, -1 / 60.0, 4.0
    lens = jl.Lens(
        (jl.Sphere(c1), jl.Sphere(c2)),
        jnp.array([t, 50.0]),
        (jl.ModelGlass(n, np.inf), jl.ModelGlass(n_img, np.inf)),
        epd=5.0,
        fields=[0.0, 5.0],
        wavelengths=[0.5875618],
    )
    p1, p2 = (n - 1) * c1, (n_img - n) * c2
    power = p1 + p2 - t / n * p1 * p2
    pd = jl.paraxial_data(lens)
    assert float(pd.efl) == pytest.approx(1 / power, rel=1e-13)
    assert float(pd.efl_image_space) == pytest.approx(n_img / power, rel=1e-13)
    data = report.report_data(lens)
    assert data["efl"] == pytest.approx(1 / power, rel=1e-13)
    assert data["efl_image_space"] == pytest.approx(n_img / power, rel=1e-13)
    text = report.format_report(data)
    row = {
        line.split(":")[0].strip(): float(line.split(":")[1].split()[0])
        for line in text.splitlines()
        if line.startswith("  Effective focal")
    }
    assert row == {
        "Effective focal length (in air)": pytest.approx(1 / power, rel=1e-6),
        "Effective focal length (img space)": pytest.approx(n_img / power, rel=1e-6),
    }


# ---------------------------------------------------------------------------- writing


def _window_and_singlet():
    """A flat N-BK7 window clipped at 3 mm, then a singlet (front surface clipped at 4 mm)
    whose image space is N-BK7."""
    bk7 = jl.get_material("N-BK7")
    return jl.Lens(
        (jl.Plane(3.0), jl.Plane(), jl.Sphere(1 / 40.0, 4.0), jl.Sphere(-1 / 60.0)),
        jnp.array([2.0, 1.0, 4.0, 30.0]),
        (bk7, jl.Air(), jl.ModelGlass(1.6, 40.0), bk7),
        stop=2,
        epd=5.0,
        wavelengths=[0.5875618],
        image=jl.Standard(c=0.0, k=0.0, semi_diameter=9.0),
    )


def _axial_rays(heights):
    h = jnp.asarray(heights)
    origin = jnp.stack([jnp.zeros_like(h), h, jnp.full_like(h, -1.0)], -1)
    direction = jnp.broadcast_to(jnp.array([0.0, 0.0, 1.0]), origin.shape)
    return jl.Rays(origin, direction, 0.5875618)


def _blocks(text):
    """{surface number: [lines]} of a .zmx text."""
    out, cur = {}, None
    for line in text.splitlines():
        if line.startswith("SURF "):
            cur = out.setdefault(int(line.split()[1]), [])
        elif cur is not None:
            cur.append(line.strip())
    return out


def test_save_writes_clipping_as_clap_and_the_image_medium(tmp_path):
    from test_lensfile import assert_same_lens

    lens = _window_and_singlet()
    path = tmp_path / "clipped.zmx"
    jl.save(lens, path)
    text = path.read_text()
    blocks = _blocks(text)
    # Zemax's circular aperture, CLAP min max 0, on exactly the clipped surfaces.
    claps = {n: [x for x in b if x.startswith("CLAP")] for n, b in blocks.items()}
    assert claps == {
        0: [],
        1: ["CLAP 0 3.0E+000 0"],
        2: [],
        3: ["CLAP 0 4.0E+000 0"],
        4: [],
        5: ["CLAP 0 9.0E+000 0"],
    }
    # The image surface names image space's medium, as the last lens surface does.
    glas = [x.split()[1] for x in blocks[5] if x.startswith("GLAS")]
    assert glas == ["N-BK7"] == [x.split()[1] for x in blocks[4] if x.startswith("GLAS")]
    back = jl.load(path)
    # load -> save -> load is exact (the .zmx reader's lens traces by Zemax's rule).
    assert back.negative_propagation
    assert_same_lens(dataclasses.replace(lens, negative_propagation=True), back)
    # The clipping is in the CLAP lines alone (all that Zemax and optiland clip with).
    (tmp_path / "clap_only.zmx").write_text(
        "\n".join(x for x in text.splitlines() if not x.strip().startswith("DIAM")) + "\n"
    )
    clap_only = jl.load(tmp_path / "clap_only.zmx")
    assert [float(s.semi_diameter) for s in clap_only.surfaces] == [3.0, np.inf, 4.0, np.inf]
    # Known answer: rays parallel to the axis at 2.9 mm pass the 3 mm window, at 3.1 mm not.
    rays = _axial_rays([0.0, 2.9, 3.1])
    for clipped in (lens, back, clap_only):
        np.testing.assert_array_equal(
            np.asarray(jl.trace(clipped, rays).valid), [True, True, False]
        )
    assert bool(jl.trace(unclipped(lens), rays).valid.all())
    n_img = float(jl.get_material("N-BK7").index(0.5875618))
    pd = jl.paraxial_data(back)
    assert float(pd.efl_image_space) == pytest.approx(n_img * float(pd.efl), rel=1e-15)
    assert float(pd.efl_image_space) == float(jl.paraxial_data(lens).efl_image_space)


# ---------------------------------------------------------------------------- reading

SINGLET_C1, SINGLET_C2, SINGLET_T, SINGLET_N = 1 / 50.0, -1 / 50.0, 5.0, 1.5


def _singlet_efl_bfl():
    p1, p2 = (SINGLET_N - 1) * SINGLET_C1, (1 - SINGLET_N) * SINGLET_C2
    f = 1 / (p1 + p2 - SINGLET_T / SINGLET_N * p1 * p2)
    return f, f * (1 - SINGLET_T * p1 / SINGLET_N)


def _file(system, surface1="", image_surface="", obj="  DISZ INFINITY\n", image_gap=None):
    """A stop-in-front singlet (model glass n = 1.5, no dispersion) as .zmx text."""
    bfl = _singlet_efl_bfl()[1] if image_gap is None else image_gap
    return (
        f"UNIT MM\n{system}WAVM 1 0.5875618 1\nSURF 0\n{obj}"
        f"SURF 1\n  STOP\n  CURV {SINGLET_C1!r}\n  DISZ {SINGLET_T!r}\n"
        f"  GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0 0\n{surface1}"
        f"SURF 2\n  CURV {SINGLET_C2!r}\n  DISZ {bfl!r}\nSURF 3\n{image_surface}"
    )


def _load_text(tmp_path, text, name="f.zmx"):
    p = tmp_path / name
    p.write_text(text)
    return p, jl.load(p)


def _refused(tmp_path, text, match):
    """The ValueError's message, checked to name the file, the line and the line's text."""
    p = tmp_path / "bad.zmx"
    p.write_text(text)
    with pytest.raises(ValueError, match=match) as e:
        jl.load(p)
    msg = str(e.value)
    number = int(msg[len(str(p)) + 1 :].split(":")[0])
    assert msg.startswith(f"{p}:{number}: ")
    assert repr(text.splitlines()[number - 1].strip()) in msg
    return text.splitlines()[number - 1].strip()


def test_object_space_na_and_cone_angle(tmp_path):
    """OBNA v 0: EPD = 2·d·tan(asin(NA/n)); OBNA v 1: EPD = 2·d·tan(u), with d the distance
    from the object to the entrance pupil (here the stop on surface 1, 200 mm away)."""
    obj = "  DISZ 200\n"
    _, na = _load_text(tmp_path, _file("OBNA 0.1 0\n", obj=obj))
    assert float(na.epd) == pytest.approx(2 * 200 * 0.1 / np.sqrt(1 - 0.01), rel=1e-14)
    _, cone = _load_text(tmp_path, _file("OBNA 5 1\n", obj=obj))
    assert float(cone.epd) == pytest.approx(2 * 200 * np.tan(np.radians(5.0)), rel=1e-14)
    # In water (n = 1.333) the same NA is a smaller angle.
    water = "  DISZ 200\n  GLAS ___BLANK 1 0 1.333 0 0 0 0 0 0 0\n"
    _, wet = _load_text(tmp_path, _file("OBNA 0.1 0\n", obj=water))
    u = np.arcsin(0.1 / 1.333)
    assert float(wet.epd) == pytest.approx(2 * 200 * np.tan(u), rel=1e-13)
    assert _refused(tmp_path, _file("OBNA 0.1 0\n"), "needs a finite object") == "OBNA 0.1 0"
    assert _refused(tmp_path, _file("OBNA 1.2 0\n", obj=obj), r"NA must be in \(0, n\)")
    assert _refused(tmp_path, _file("OBNA 0.1 3\n", obj=obj), "OBNA type must be 0")


def test_paraxial_image_height_fields(tmp_path):
    """FTYP 2: the image surface is at the paraxial focus, so a paraxial image height h is
    the field θ = atan(h / EFL) (object at infinity, in air)."""
    efl, _ = _singlet_efl_bfl()
    system = "ENPD 10\nFTYP 2 0 3 1 0 0 0\nXFLN 0 0 2\nYFLN 0 5 -3\n"
    _, lens = _load_text(tmp_path, _file(system))
    want = np.degrees(np.arctan(np.array([[0.0, 0.0], [0.0, 5.0], [2.0, -3.0]]) / efl))
    np.testing.assert_allclose(np.asarray(lens.fields), want, rtol=1e-14, atol=0)
    heights = jl.paraxial.image_height(lens, lens.fields[:, 1])
    np.testing.assert_allclose(np.asarray(heights), [0.0, 5.0, -3.0], rtol=0, atol=1e-12)
    # In centimetres the heights are 10x larger in mm.
    cm = _file(system).replace("UNIT MM", "UNIT CM")
    cm_lens = _load_text(tmp_path, cm)[1]
    np.testing.assert_allclose(
        np.asarray(jl.paraxial.image_height(cm_lens, cm_lens.fields[:, 1])),
        [0.0, 50.0, -30.0],
        rtol=0,
        atol=1e-11,
    )


def test_object_height_fields_put_the_object_points_there(tmp_path):
    """FTYP 1 with an object 200 mm away: each field becomes the angle whose object point
    (``sampling.object_point``) lies at the file's object height, (x, y) = (0, 5) and
    (2, −3) mm."""
    from jaxlens.imaging import sampling

    text = _file("ENPD 10\nFTYP 1 0 2 1 0 0 0\nXFLN 0 2\nYFLN 5 -3\n", obj="  DISZ 200\n")
    _, lens = _load_text(tmp_path, text)
    for field, want in zip(np.asarray(lens.fields), [(0.0, 5.0), (2.0, -3.0)], strict=True):
        p = np.asarray(sampling.object_point(lens, jnp.asarray(field), 200.0))
        np.testing.assert_allclose(p, [want[0], want[1], -200.0], rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("ftyp", "match"),
    [
        ("FTYP 1 0 2 1 0 0 0", r"object heights \(FTYP 1\) need a finite object distance"),
        ("FTYP 4 0 2 1 0 0 0", r"field type 4 \(theodolite angles\)"),
        ("FTYP 0 1 2 1 0 0 0", "object-space telecentric"),
        ("FTYP 2 0 2 1 0 0 1", r"field type 2 \(paraxial image heights\) with an afocal image "
                               r"space .*has no heights"),
        ("FTYP 0 0 2 1 0 0 2", r"afocal image space flag \(FTYP's seventh value\) must be 0 "
                               r"or 1, got 2"),
    ],
)
def test_field_types_refused_with_the_line(tmp_path, ftyp, match):
    text = _file(f"ENPD 10\n{ftyp}\nYFLN 0 5\n")
    assert _refused(tmp_path, text, match) == ftyp


def test_vignetting_factors_read_on_used_fields(tmp_path):
    """Vignetting factors on a used field are read into ``Lens.vignetting`` (VDX, VDY, VCX,
    VCY, VAN columns), strict or not and without a word; all zero reads as None. Its paraxial
    data do not depend on them."""
    head = "ENPD 10\nFTYP 0 0 2 1 0 0 0\nYFLN 0 5 0 0\n"
    zeros = "VDXN 0 0 0 0\nVDYN 0 0 0 0\nVCXN 0 0 0 0\nVCYN 0 0 0 0\nVANN 0 0 0 0\n"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, plain = _load_text(tmp_path, _file(head + zeros))  # all zero: nothing to report
        _load_text(tmp_path, _file(head + zeros.replace("VCYN 0 0 0 0", "VCYN 0 0 0.5 0")))
    assert plain.vignetting is None
    for j, key in enumerate(("VDXN", "VDYN", "VCXN", "VCYN", "VANN")):
        given = _file(head + zeros.replace(f"{key} 0 0 0 0", f"{key} 0 0.25 0 0"))
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            _, lens = _load_text(tmp_path, given)
            strict = jl.load(tmp_path / "f.zmx", strict=True)
        want = np.zeros((2, 5))
        want[1, j] = 0.25
        np.testing.assert_array_equal(np.asarray(lens.vignetting), want)
        np.testing.assert_array_equal(np.asarray(strict.vignetting), want)
        assert float(jl.paraxial_data(lens).efl) == float(jl.paraxial_data(plain).efl)


def _axial_valid(lens, heights):
    """Which rays parallel to the axis, at these heights (mm) in y, reach the image."""
    h = jnp.asarray(heights)
    o = jnp.stack([jnp.zeros_like(h), h, jnp.full_like(h, -1.0)], -1)
    d = jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0]), o.shape)
    return np.asarray(jl.trace(lens, jl.Rays(o, d, 0.5875618)).valid).tolist()


def test_central_obscuration_blocks_the_rays_inside_it(tmp_path):
    # OBSC 0 2 on surface 1 (the stop): rays meeting it within 2 mm of the axis are blocked,
    # the others pass, and a written file reads back with the same obscuration.
    p, lens = _load_text(tmp_path, _file("ENPD 10\n", surface1="  OBSC 0 2 0\n"))
    assert lens.obscurations == ((0, 0.0, 2.0),)
    assert _axial_valid(lens, [0.0, 1.0, 1.99, 2.01, 3.0, 4.9]) == [False] * 3 + [True] * 3
    jl.save(lens, tmp_path / "again.zmx")
    assert jl.load(tmp_path / "again.zmx").obscurations == lens.obscurations
    with pytest.raises(ValueError, match="OBSC needs 0 ≤ minimum < maximum"):
        _load_text(tmp_path, _file("ENPD 10\n", surface1="  OBSC 3 2 0\n"))
    assert json_round_trip(lens, tmp_path).obscurations == lens.obscurations


def test_annular_aperture_passes_only_its_ring(tmp_path):
    """CLAP 1 4 (an annulus): rays meeting the surface within 1 mm of the axis are blocked
    (a central obscuration) and beyond 4 mm clipped; a written file reads back the same."""
    _, lens = _load_text(tmp_path, _file("ENPD 10\n", surface1="  CLAP 1 4 0\n"))
    assert lens.obscurations == ((0, 0.0, 1.0),)
    assert float(lens.surfaces[0].semi_diameter) == 4.0
    assert _axial_valid(lens, [0.0, 0.99, 1.01, 3.0, 3.99, 4.01]) == [False, False] + [True] * 3 + [
        False]
    jl.save(lens, tmp_path / "again.zmx")
    again = jl.load(tmp_path / "again.zmx")
    assert again.obscurations == lens.obscurations
    assert float(again.surfaces[0].semi_diameter) == 4.0
    with pytest.raises(ValueError, match="annular aperture needs minimum < maximum"):
        _load_text(tmp_path, _file("ENPD 10\n", surface1="  CLAP 5 4 0\n"))
    with pytest.raises(ValueError, match="annular aperture .CLAP. and an obscuration"):
        _load_text(tmp_path, _file("ENPD 10\n", surface1="  CLAP 1 4 0\n  OBSC 0 0.5 0\n"))


def test_other_apertures_refused(tmp_path):
    ep = "ENPD 10\n"
    # An obscuration of radius 0 obscures nothing; OBSC is no longer read as a system aperture.
    _, lens = _load_text(tmp_path, _file(ep, surface1="  OBSC 0 0 0\n"))
    assert float(lens.epd) == 10.0
    # A decentered circular aperture (OBDC) is read as a decentered circle that alone clips.
    _, lens = _load_text(tmp_path, _file(ep, surface1="  CLAP 0 4 0\n  OBDC 0 0.5\n"))
    assert lens.apertures == ((0, jl.Aperture.circle(4.0, 0.0, 0.5)),)
    assert float(lens.surfaces[0].semi_diameter) == np.inf
    assert _axial_valid(lens, [-3.49, -3.51, 4.49, 4.51]) == [True, False, True, False]
    _, lens = _load_text(tmp_path, _file(ep, surface1="  CLAP 0 4 0\n  OBDC 0 0\n"))
    assert float(lens.surfaces[0].semi_diameter) == 4.0
    assert lens.apertures == ()
    # A decenter of a surface that clips nothing (an automatic DIAM, solve flag 0, as in an
    # off-axis mirror system's file, or a fixed DIAM with no aperture, which clips nothing
    # in Zemax) has nothing to move: ignored. A floating aperture (FLAP) clips at the fixed
    # DIAM, and with no aperture for the decenter to move it is refused.
    _, lens = _load_text(tmp_path, _file(ep, surface1='  DIAM 6 0 0 0 1 ""\n  OBDC 0 -3\n'))
    assert float(lens.surfaces[0].semi_diameter) == np.inf
    _, lens = _load_text(tmp_path, _file(ep, surface1='  DIAM 6 1 0 0 1 ""\n  OBDC 0 -3\n'))
    assert float(lens.surfaces[0].semi_diameter) == np.inf
    assert lens.apertures == ()
    assert _refused(tmp_path, _file(ep, surface1='  DIAM 6 1 0 0 1 ""\n  FLAP 0 6 0\n'
                                                  '  OBDC 0 -3\n'),
                    "decenter .OBDC. of a floating aperture") == "OBDC 0 -3"
    # A decentered annular obscuration has no Lens form.
    assert _refused(tmp_path, _file(ep, surface1="  OBSC 1 2 0\n  OBDC 0 -3\n"),
                    "decentered .OBDC. annular obscuration") == "OBSC 1 2 0"


def test_ray_aiming_and_image_medium_are_reported(tmp_path):
    from jaxlens.io.zmx import ZmxWarning

    _load_text(tmp_path, _file("ENPD 10\nRAIM 0 0 1 1 0 0 0 0 0\n"))  # aiming off: silent
    # Type 2 (Zemax's "Real" aiming) is Lens.aim "real_marginal", without a word
    # (tests/test_ray_aiming*.py: the other types and what each does).
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, lens = _load_text(tmp_path, _file("ENPD 10\nRAIM 0 2 1 1 0 0 0 0 0\n"))
    assert lens.aim == "real_marginal"
    with pytest.warns(
        ZmxWarning,
        match=r"the image surface names N-BK7 but image space .* "
        r"is AIR; jaxlens uses AIR",
    ):
        _, lens = _load_text(tmp_path, _file("ENPD 10\n", image_surface="  GLAS N-BK7\n"))
    assert lens.materials[-1] == jl.Air()


def test_rectangular_and_elliptical_apertures_are_read(tmp_path):
    """SQAP/ELAP (once ignored with a warning) are read as Lens.apertures and clip, silently
    even under strict; half-widths that are not > 0 are refused."""
    for line, shape in (("SQAP 3 4 0", "rect"), ("ELAP 3 4 0", "ellipse")):
        text = _file("ENPD 10\n", surface1=f"  {line}\n")
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            _, lens = _load_text(tmp_path, text)
        assert lens.apertures == ((0, jl.Aperture(shape, 3.0, 4.0)),)
        assert _axial_valid(lens, [3.99, 4.01]) == [True, False]
        assert jl.io.zmx.loads(text, "f.zmx", strict=True).apertures == lens.apertures
        assert _refused(tmp_path, text.replace(line, line.replace("3", "0")),
                        "needs half-widths > 0") == line.replace("3", "0")


def test_image_surface_model_glass_must_match_image_space(tmp_path):
    from jaxlens.io.zmx import ZmxWarning

    last = "  GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0 0\n"  # surface 2 into the same model glass
    text = _file("ENPD 10\n").replace(
        f"  DISZ {_singlet_efl_bfl()[1]!r}\n", f"  DISZ {_singlet_efl_bfl()[1]!r}\n{last}"
    )
    _load_text(tmp_path, text + last)  # the same model glass: silent
    with pytest.warns(ZmxWarning, match="names ___BLANK 1.6 0 but image space .* is ___BLANK"):
        _load_text(tmp_path, text + last.replace("1.5", "1.6"))


def test_older_zemax_xfld_yfld_fields(tmp_path):
    """Zemax files before XFLN/YFLN list the fields as XFLD/YFLD, one value a field (FTYP
    without a count). They were read as a single on-axis field; XFLN without YFLN is
    refused rather than dropped."""
    old = "ENPD 10\nFTYP 0 0\nXFLD 0 0 3\nYFLD 0 10 20\nFWGT 1 1 1\n"
    _, lens = _load_text(tmp_path, _file(old))
    np.testing.assert_array_equal(np.asarray(lens.fields), [[0, 0], [0, 10], [3, 20]])
    _, lens = _load_text(tmp_path, _file(old.replace("XFLD 0 0 3\n", "")))
    np.testing.assert_array_equal(np.asarray(lens.fields), [0, 10, 20])
    # XFLN/YFLN win where a file has both (Zemax 2005-2013 wrote both).
    both = old + "XFLN 0 0 0 0 0 0 0 0 0 0 0 0\nYFLN 0 7 0 0 0 0 0 0 0 0 0 0\n"
    _, lens = _load_text(tmp_path, _file(both.replace("FTYP 0 0", "FTYP 0 0 2 1")))
    np.testing.assert_array_equal(np.asarray(lens.fields), [0, 7])
    assert _refused(tmp_path, _file("ENPD 10\nXFLN 0 5\n"), "without the y fields") == "XFLN 0 5"


def test_parameters_on_a_standard_surface(tmp_path):
    """A block without TYPE is STANDARD: with asphere terms (PARM ≠ 0) its TYPE line is
    missing, and reading it as a sphere would drop them silently, so it is refused. Under an
    explicit TYPE STANDARD, Zemax ignores left-over parameters, and so does the reader."""
    parm = "  PARM 2 1.5E-5\n"
    assert _refused(tmp_path, _file("ENPD 10\n", surface1=parm), "has no TYPE line") == (
        "PARM 2 1.5E-5")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, lens = _load_text(tmp_path, _file("ENPD 10\n", surface1="  TYPE STANDARD\n" + parm))
    assert float(jl.paraxial_data(lens).efl) == pytest.approx(_singlet_efl_bfl()[0], rel=1e-14)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _load_text(tmp_path, _file("ENPD 10\n", surface1="  PARM 1 0\n  PARM 2 0\n"))


def test_model_glass_partial_dispersion_reported(tmp_path):
    """GLAS ___BLANK 1 0 nd Vd ΔPgF: a ΔPgF other than 0 is not modelled (the index off the
    d line differs from Zemax's): a warning naming the line."""
    text = _file("ENPD 10\n").replace("___BLANK 1 0 1.5 0 0", "___BLANK 1 0 1.5 50 0.02")
    with pytest.warns(zmx.ZmxWarning, match=r"f.zmx:10: model glass ΔPgF 0.02 ignored"):
        _load_text(tmp_path, text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _load_text(tmp_path, text.replace("50 0.02", "50 0"))


def test_a_semi_diameter_beyond_the_sphere_is_refused_naming_the_surface(tmp_path):
    """A floating aperture at a fixed DIAM wider than the sphere itself (|R| < DIAM) has no
    surface to clip at: the lens class refuses it, and the reader reports that with the
    surface's line. (A DIAM alone clips nothing, so it is not refused.)"""
    r = 1 / abs(SINGLET_C1)
    line = _refused(tmp_path, _file("ENPD 10\n", surface1=f"  DIAM {2 * r!r} 1\n  FLAP 0 1 0\n"),
                    r"is defined only out to r = .* semi_diameter")
    assert line == "SURF 1"
    _load_text(tmp_path, _file("ENPD 10\n", surface1=f"  DIAM {0.5 * r!r} 1\n  FLAP 0 1 0\n"))
    _, lens = _load_text(tmp_path, _file("ENPD 10\n", surface1=f"  DIAM {2 * r!r} 1\n"))
    assert float(lens.surfaces[0].semi_diameter) == np.inf
