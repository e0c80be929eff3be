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
TOP = 9.0  # the optic's largest field (mm): the blobs' Hermite points stay within it


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
    out = dict(source="optiland 0.6.3, tools/tele43a_reference.py", name=NAME,
               zmx=f"tests/data/tele42a/{NAME}.zmx", semi_diameters="none (open lens)",
               wavelength_um=t42.PRIMARY, paraxial_magnification=float(m),
               n_hermite=N_HERMITE, blobs=blobs)
    (OUT_DIR / f"{NAME}_blobs.json").write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
