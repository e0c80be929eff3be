"""Shared test helpers: build lenses from the reference-case files without the file loaders."""

from __future__ import annotations

import importlib.util
import json
import pathlib
import sys

import jax.numpy as jnp
import numpy as np

import jaxlens as jl


def _shape(s):
    """The surface of a refcase entry: curvature, conic and [A2, A4, ...]."""
    co = s.get("even_asphere_coeffs") or []
    c, k = s.get("curvature", 0.0), s.get("conic", 0.0)
    return jl.EvenAsphere(c=c, k=k, coeffs=co) if co else jl.Standard(c=c, k=k)


def _table(n):
    return jl.Tabulated(np.array([float(w) / 1000 for w in n]), np.array(list(n.values())))


def refcase_lens(path) -> tuple[jl.Lens, dict]:
    """A Lens from a refcase JSON (tabulated indices), and the raw case.

    Every schema field that changes a trace is used: each surface's curvature, conic and
    even-asphere terms (the image surface's too), the media after each surface, the
    object-space medium (surface 0's ``n``) when it is not air, and a finite object's
    distance (surface 0's ``thickness``; the analyses trace its fields from there). The
    medium after the image surface is not part of a Lens; ``refcase_rays`` accounts for it.
    The lens has ``negative_propagation``: the cases' tracers (optiland, rayoptics, as Zemax)
    clip no ray, and take a rim ray back along its line to a surface whose sag crosses the one
    before it (tests/data/fuzz36b/crossing); jaxlens's default flags such a ray."""
    d = json.loads(pathlib.Path(path).read_text())
    surfs, th, mats, stop = [], [], [], 0
    for s in d["surfaces"][1:-1]:
        surfs.append(_shape(s))
        th.append(s["thickness"])
        mats.append(_table(s["n"]))
        if s.get("is_stop"):
            stop = len(surfs) - 1
    if not any(s.get("is_stop") for s in d["surfaces"]) and "stop_surface_index" in d:
        stop = d["stop_surface_index"] - 1
    obj = d["surfaces"][0].get("n") or {}
    extra = {} if all(v == 1.0 for v in obj.values()) else {"object_material": _table(obj)}
    dist = _object_distance(d)
    if dist is not None:
        extra["object_distance"] = dist
    img = d["surfaces"][-1]
    wls = np.array(d["wavelengths_nm"]) / 1000
    lens = jl.Lens(
        surfaces=tuple(surfs),
        thickness=jnp.array(th),
        materials=tuple(mats),
        stop=stop,
        epd=d["aperture"]["EPD"],
        wavelengths=wls,
        primary=int(np.argmin(np.abs(wls - d["primary_wavelength_nm"] / 1000))),
        fields=jnp.array(d["fields"]["values"]),
        image=_shape(img),
        negative_propagation=True,
        **extra,
    )
    return lens, d


def _object_distance(d):
    """A finite object's distance (mm): surface 0's ``thickness``, else ``object.distance``;
    None for an object at infinity ("inf", "infinity", or 1e10 mm and more, as in a Lens)."""
    t = d["surfaces"][0].get("thickness", (d.get("object") or {}).get("distance", "inf"))
    t = float(t)  # "inf" and "infinity" parse
    return None if t >= jl.optics.lens.INFINITE_OBJECT_MM else t


def _image_normal(img, x, y):
    """Unit normals (pointing +z) of the image surface at local (x, y) [N, 3] (numpy)."""
    c, k = img.get("curvature", 0.0), img.get("conic", 0.0)
    r2 = x * x + y * y
    slope = c / np.sqrt(1.0 - (1.0 + k) * c * c * r2)  # (dz/dr)/r of the conic
    for i, a in enumerate(img.get("even_asphere_coeffs") or [], start=1):
        slope = slope + 2 * i * a * r2 ** (i - 1)
    nrm = np.stack([-x * slope, -y * slope, np.ones_like(x)], -1)
    return nrm / np.linalg.norm(nrm, axis=-1, keepdims=True)


def _undo_image_refraction(d, ref):
    """Reference directions in image space (where a trace ends).

    When the image surface's own medium (its ``n``, the medium AFTER it) differs from image
    space (the ``n`` of the last lens surface), the stored directions are after a refraction
    at the image surface (optiland refracts there); Snell's law is reversible, so they are
    refracted back, exactly, with the image surface's normal at the stored intercept."""
    img, last = d["surfaces"][-1], d["surfaces"][-2]
    if "n" not in img:
        return ref
    key = {float(w): w for w in last["n"]}
    n1 = np.array([last["n"][key[float(r["wavelength_nm"])]] for r in d["real_rays"]])
    key2 = {float(w): w for w in img["n"]}
    n2 = np.array([img["n"][key2[float(r["wavelength_nm"])]] for r in d["real_rays"]])
    if np.all(n1 == n2):
        return ref
    nrm = _image_normal(img, ref[:, 0], ref[:, 1])
    v = ref[:, 3:]
    cos2 = np.sum(v * nrm, -1, keepdims=True)
    tangential = (n2 / n1)[:, None] * (v - cos2 * nrm)
    cos1 = np.sign(cos2) * np.sqrt(1.0 - np.sum(tangential**2, -1, keepdims=True))
    out = ref.copy()
    out[:, 3:] = np.where((n1 == n2)[:, None], v, tangential + cos1 * nrm)
    return out


def refcase_rays(d, dtype=jnp.float64):
    """The reference real rays (launch) and their expected image data [N, 6]."""
    o, v, w, ref = [], [], [], []
    for r in d["real_rays"]:
        o.append(r["launch"]["point_on_EP_plane"])
        v.append(r["launch"]["direction_cosines"])
        w.append(r["wavelength_nm"] / 1000)
        im = r["image"]
        ref.append([im["x"], im["y"], im["z"], im["L"], im["M"], im["N"]])
    rays = jl.Rays(jnp.array(o, dtype), jnp.array(v, dtype), jnp.array(w, dtype))
    return rays, _undo_image_refraction(d, np.array(ref))


def json_round_trip(lens: jl.Lens, folder) -> jl.Lens:
    """``lens`` saved as JSON in ``folder`` and loaded again, checked equal to it: the same
    structure (surface kinds, mirrors, apertures, …) and the same leaves, bit for bit."""
    import jax

    path = pathlib.Path(folder) / "round_trip.json"
    jl.save(lens, path)
    again = jl.load(path)
    assert jax.tree_util.tree_structure(again) == jax.tree_util.tree_structure(lens)
    for a, b in zip(jax.tree_util.tree_leaves(again), jax.tree_util.tree_leaves(lens), strict=True):
        np.testing.assert_array_equal(np.asarray(a, np.float64), np.asarray(b, np.float64))
    return again


def check_corpus_tool():
    """tools/check_corpus.py (not part of the package), loaded once from the repository."""
    if "check_corpus" not in sys.modules:
        path = pathlib.Path(__file__).resolve().parents[1] / "tools" / "check_corpus.py"
        spec = importlib.util.spec_from_file_location("check_corpus", path)
        module = importlib.util.module_from_spec(spec)
        sys.modules["check_corpus"] = module
        spec.loader.exec_module(module)
    return sys.modules["check_corpus"]


def load_recording(path, **kw) -> tuple[jl.Lens, list]:
    """``jl.load(path, **kw)`` with every warning recorded: the lens and the warnings (their
    ``warnings.WarningMessage`` records, in order)."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        lens = jl.load(path, **kw)
    return lens, list(caught)


def image_xy(lens: jl.Lens, fields_deg, beam, pupil, launch, wavelength) -> list:
    """jaxlens's image intercepts (x, y) of collimated rays at each field angle (deg, in y),
    through the pupil points (fractions of ``beam``/2, mm) on the plane ``launch`` mm from
    surface 1 (negative: before it), every aperture removed; NaN where a ray is lost. The
    rays of the round 40a–45c reference tools (tools/zmx43d_reference.py ``trace``)."""
    import math

    import jax

    from jaxlens.optics.lens import unclipped

    r = 0.5 * beam
    out = []
    for f in fields_deg:
        t = math.tan(math.radians(f))
        d = np.array([0.0, t, 1.0]) / math.sqrt(1 + t * t)
        o = np.array([[px * r, py * r - launch * t, launch] for px, py in pupil])
        with jax.disable_jit():  # a few small traces: faster than compiling
            res = jl.trace(unclipped(lens), jl.Rays(o, np.tile(d, (len(o), 1)), wavelength))
        xy = np.asarray(res.origin)[:, :2]
        out.append(np.where(np.asarray(res.valid)[:, None], xy, np.nan))
    return out


def check_first_order(p, fo: dict, *, sizes: bool = True) -> None:
    """jaxlens's paraxial data ``p`` (``jl.paraxial_data``) against optiland's first-order
    record ``fo`` (the reference tools' ``first_order``: f2, F2 and XPL from the image
    surface, EPL from surface 1, EPD, XPD, FNO). ``sizes`` False leaves out the pupils'
    diameters and the F/#. optiland's XPD carries the pupil magnification's sign (negative
    where the exit pupil is inverted); jaxlens's is the diameter."""
    import pytest

    image_z = float(p.image_z)
    assert float(p.efl_image_space) == pytest.approx(fo["f2"], rel=1e-12)
    assert float(p.paraxial_image_z) - image_z == pytest.approx(fo["F2"], abs=1e-10)
    assert float(p.entrance_pupil_z) == pytest.approx(fo["EPL"], abs=1e-10)
    assert float(p.exit_pupil_z) - image_z == pytest.approx(fo["XPL"], abs=1e-9)
    if sizes:
        assert float(p.entrance_pupil_diameter) == pytest.approx(fo["EPD"], rel=1e-12)
        assert float(p.exit_pupil_diameter) == pytest.approx(abs(fo["XPD"]), rel=1e-10)
        assert float(p.fnum) == pytest.approx(fo["FNO"], rel=1e-12)


def image_miss(got: list, want: list) -> float:
    """The largest |jaxlens − reference| (mm) over image intercepts: ``got`` as
    ``image_xy`` returns them, ``want`` the reference's rows ([x, y] or None where its ray
    was lost), the same rays lost in both (asserted)."""
    worst = 0.0
    for g, w in zip(got, want, strict=True):
        w = np.array([[np.nan, np.nan] if v is None else v for v in w])
        assert np.array_equal(np.isnan(g[:, 0]), np.isnan(w[:, 0]))
        worst = max(worst, float(np.nanmax(np.abs(g - w))))
    return worst
