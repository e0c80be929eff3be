"""Reference numbers for rendering an object-space telecentric lens (round 43a), from optiland
0.6.3: where the light of a small Gaussian object blob lands.

Run with the optiland environment's interpreter, from the repository root:

    /work/optenv/bin/python tools/tele43a_reference.py

It writes tests/data/tele43a/tele_triplet_far_blobs.json for round 42a's ``tele_triplet_far``
(tests/data/tele42a/tele_triplet_far.zmx: a triplet at m ≈ −0.67, NA 0.02, 9 % distortion at
10 mm), built through optiland's API as ``tools/tele42a_reference.py`` builds it, with the
stop and image gaps of tests/data/tele42a/tele_triplet_far.json and without semi-diameters
(optiland's lens has none: every ray of the NA cone passes). jaxlens is not imported here.

For each blob (an object radiance exp(−|X − X0|²/(2σ²)) on the object plane, X in mm) the
flux-weighted mean landing point of its light on the image surface, at the primary wavelength:

    c = ∫∫ f(X) x(X, ray) dΩ dX / ∫∫ f(X) dΩ dX,

X over the blob by a Gauss–Hermite rule (``N_HERMITE`` points per axis), the rays over the
object cone uniformly in projected solid angle (direction cosines): optiland launches the
slopes (Px, Py)·tan u, so a Gauss rule over the unit pupil disc (``tele42a_reference.disc_rule``)
is weighted by cos⁴γ = 1/(1 + |s|²)², the Jacobian from slopes to direction cosines. Every
object point's cone passes whole, so its flux is the same per unit radiance and area. This
is the first moment of the irradiance a render of the blob gives (its pixels' irradiance
times their position, summed), whatever the blob's size: no small-blob approximation. Also
each blob centre's real chief ray (parallel to the axis) and ``m·X0``.

``ri_point``: the relative irradiance that a uniform object gives at the image points of the
chief rays of the heights 5 and 10 mm: E(x) = L·Σ_s w_s/|det ∂x/∂X| over the pupil rays s
that land at x (each from its own object point, found by Newton's method on optiland's rays,
the Jacobian by central differences), relative to the axis's. This is the irradiance at a
point; round 42a's ``ri_open`` is the flux of an object patch over the area of its beam
centroid's image (1/|det| of the mean instead of the mean of 1/|det|), which differs where
the per-ray magnification varies over the pupil (0.7 % at 10 mm on this lens).
"""

import json
import math
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import tele42a_reference as t42  # noqa: E402  (its optiland builder)

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT_DIR = ROOT / "tests" / "data" / "tele43a"
NAME = "tele_triplet_far"
N_HERMITE = 12
SIGMA = 0.45  # mm on the object plane: its image (|m| 0.67) about 2 sensor pixels of 0.15 mm
CENTRES = [(0.0, 0.0), (0.0, 2.5), (-2.0, 1.5), (1.2, -2.2)]  # mm, object plane
TOP = 12.0  # the optic's largest field (mm): every object point traced stays within it


STEP = 1e-4  # mm, central differences of the landing point in the object point


def landing(op, X, px, py):
    r = op.trace_generic(X[:, 0] / TOP, X[:, 1] / TOP, px, py, t42.PRIMARY)
    return np.stack([np.ravel(np.asarray(r.x, float)), np.ravel(np.asarray(r.y, float))], -1)


def irradiance_at(op, target, px, py, w, m, iters=6):
    """Σ_s w_s / |det ∂x/∂X| over the pupil rays s that land at ``target`` (mm): the
    irradiance there of a uniform Lambertian object, up to L (radiance is conserved along
    each ray, so E(x) = L·Ω(x), the image-side projected solid angle of the rays reaching x,
    and Ω(x) = Σ_s w_s / |det ∂x/∂X| by the change of variables from the object point)."""
    X = np.tile(target / m, (px.size, 1))
    for _ in range(iters):
        x0 = landing(op, X, px, py)
        jac = np.empty((px.size, 2, 2))
        for k in range(2):
            d = np.zeros(2)
            d[k] = STEP
            jac[:, :, k] = (landing(op, X + d, px, py) - landing(op, X - d, px, py)) / (2 * STEP)
        X = X - np.linalg.solve(jac, (x0 - target)[..., None])[..., 0]
    assert np.max(np.abs(landing(op, X, px, py) - target)) < 1e-10
    return float(np.sum(w / np.abs(np.linalg.det(jac))))


def main() -> None:
    OUT_DIR.mkdir(parents=True, exist_ok=True)
    s = t42.SYSTEMS[NAME]
    ref42 = json.loads((ROOT / "tests" / "data" / "tele42a" / f"{NAME}.json").read_text())
    surfaces = t42.surfaces_with(s, ref42["stop_gap"], ref42["image_gap"])
    op = t42.build(s, surfaces, [(0.0, 0.0), (0.0, TOP)])
    tu = t42.tan_u(s)
    ym, um = t42.para(op, s, 0.0, tu)
    m = t42.n_object(s) * tu / um[-1]
    px, py, wt = (a.ravel() for a in t42.disc_rule())
    w_ray = wt / (1.0 + tu * tu * (px * px + py * py)) ** 2
    t, wh = np.polynomial.hermite.hermgauss(N_HERMITE)  # ∫ e^{−t²} g(t) dt
    blobs = []
    for x0, y0 in CENTRES:
        num, den = np.zeros(2), 0.0
        for i, ti in enumerate(t):
            for j, tj in enumerate(t):
                x = x0 + math.sqrt(2.0) * SIGMA * ti
                y = y0 + math.sqrt(2.0) * SIGMA * tj
                r = op.trace_generic(x / TOP, y / TOP, px, py, t42.PRIMARY)
                rx, ry = np.ravel(np.asarray(r.x, float)), np.ravel(np.asarray(r.y, float))
                w = wh[i] * wh[j] * w_ray
                num += [np.sum(w * rx), np.sum(w * ry)]
                den += np.sum(w)
        chief = op.trace_generic(x0 / TOP, y0 / TOP, np.array([0.0]), np.array([0.0]),
                                 t42.PRIMARY)
        blobs.append(dict(centre=[x0, y0], sigma=SIGMA, centroid=list(num / den),
                          chief_xy=[float(np.ravel(chief.x)[0]), float(np.ravel(chief.y)[0])],
                          ideal=[m * x0, m * y0]))
    # The irradiance at image points (a uniform object): E(x) = L Σ_s w_s / |det ∂x/∂X|,
    # each pupil ray s from the object point X(s) whose ray lands at x (Newton on optiland's
    # rays, all pupil points at once; the Jacobian by central differences of ±STEP mm).
    ri_point = []
    targets = [(0.0, 0.0)] + [tuple(r["chief_xy"]) for r in ref42["distortion"]
                              if r["height"] in ([0.0, 5.0], [0.0, 10.0])]
    e = [irradiance_at(op, np.array(t_), px, py, w_ray, m) for t_ in targets]
    for t_, ei in zip(targets[1:], e[1:], strict=True):
        ri_point.append(dict(image_xy=list(t_), ri=float(ei / e[0])))
    out = dict(source="optiland 0.6.3, tools/tele43a_reference.py", name=NAME,
               zmx=f"tests/data/tele42a/{NAME}.zmx", semi_diameters="none (open lens)",
               wavelength_um=t42.PRIMARY, paraxial_magnification=float(m),
               n_hermite=N_HERMITE, blobs=blobs, ri_point=ri_point)
    (OUT_DIR / f"{NAME}_blobs.json").write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
