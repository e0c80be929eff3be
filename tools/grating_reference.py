"""Reference image intercepts of the three optiland DGRATING sample files, traced by optiland.

Writes ``tests/data/zmx/gratings/reference.json``, read by ``tests/test_grating.py`` (which does
not need optiland). Run it with an interpreter that has optiland 0.6.3 and jaxlens importable:

    PYTHONPATH=. /work/optiland_venv/bin/python tools/grating_reference.py

optiland 0.6.3 cannot read ``TYPE DGRATING`` ("Unsupported Zemax surface type: dgrating"), so
each file's optic is built here through optiland's API from the file's own values (as
optiland's tests build the same three systems): T = PARM 1 lines/µm → ``grating_period`` 1/T
µm, PARM 2 → ``grating_order``, grooves along x (``groove_orientation_angle`` 0). Its media
get jaxlens's indices (``check_rays.set_media``) and every aperture is removed, so the
comparison is of the grating alone.

Rays: those of ``tools/check_rays.py`` (a 7 × 7 pupil grid and the real chief ray, for each
field; every third grid ray is kept, and the chief ray), launched in front of surface 1. Two
optiland intercepts are stored per ray:

* ``optiland``: optiland as shipped. Its kernel takes the local line spacing as Λ/|f_xy|
  (f the unit grating vector in the tangent plane), which is not the spacing of lines equally
  spaced in the x–y projection where the surface normal has both an x and a y component.
* ``optiland_projected_spacing``: optiland with its local spacing set to Λ/|f_y|, the spacing
  along f of the lines y = j·Λ (equally spaced in the projection on the x–y plane, as Zemax
  defines the DGRATING); everything else is optiland's.
"""

from __future__ import annotations

import json
import os
import sys
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import check_rays as cr  # noqa: E402

import jaxlens as jl  # noqa: E402
from jaxlens.io.json_values import write_whole  # noqa: E402
from jaxlens.optics.lens import unclipped  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.join(ROOT, "tests", "data", "zmx", "gratings")
FILES = ("optiland_curved_reflective_grating.zmx", "optiland_curved_transmission_grating.zmx",
         "optiland_flat_transmission_grating.zmx")


def build(name: str, lens):
    """optiland's optic of one of the three files (their values, read by jaxlens)."""
    import optiland.backend as be
    from optiland.optic import Optic

    g = next(s for s in lens.surfaces if isinstance(s, jl.Grating))
    grating = dict(surface_type="grating", grating_period=1 / float(g.lines_per_um),
                   grating_order=int(g.order), groove_orientation_angle=0.0, is_stop=True)
    radius = be.inf if float(g.c) == 0 else 1 / float(g.c)
    optic = Optic()
    optic.surfaces.add(index=0, radius=be.inf, thickness=be.inf)
    if "reflective" in name:
        optic.surfaces.add(index=1, radius=radius, thickness=float(lens.thickness[0]),
                           conic=float(g.k), material="mirror", **grating)
        optic.surfaces.add(index=2)
    else:
        t = [float(v) for v in lens.thickness]
        optic.surfaces.add(index=1, radius=be.inf, thickness=t[0])
        optic.surfaces.add(index=2, radius=be.inf, thickness=t[1], material="N-BK7")
        optic.surfaces.add(index=3, radius=radius, thickness=t[2], conic=float(g.k), **grating)
        optic.surfaces.add(index=4)
    optic.set_aperture(aperture_type="EPD", value=float(lens.epd))
    optic.fields.set_type(field_type="angle")
    for f in np.asarray(lens.fields):
        optic.fields.add(x=float(f[0]), y=float(f[1]))
    optic.wavelengths.add(value=float(lens.wavelengths[lens.primary]), is_primary=True)
    optic.updater.update_paraxial()
    return optic


def projected_spacing(model, rays):
    """optiland's ``interact_real_rays`` with the local spacing Λ/|f_y| (see the module notes)."""
    import optiland.backend as be

    g = model.geometry
    nx, ny, nz = g.surface_normal(rays)
    n1, n2 = model.material_pre.n(rays.w), model.material_post.n(rays.w)
    fx, fy, fz = g.grating_vector(rays)
    rays.gratingdiffract(nx, ny, nz, fx, fy, fz, g.grating_order, g.grating_period / be.abs(fy),
                         n1, n2, model.is_reflective)
    return model._apply_coating_and_bsdf(rays, nx, ny, nz)


def main() -> int:
    from optiland.interactions.diffractive_model import DiffractiveInteractionModel

    shipped = DiffractiveInteractionModel.interact_real_rays
    out = {"command": "PYTHONPATH=. /work/optiland_venv/bin/python tools/grating_reference.py",
           "optiland": "0.6.3", "files": {}}
    for name in FILES:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            lens = jl.load(os.path.join(DATA, name))
        rays = []
        for field in np.asarray(lens.fields):
            wl = float(lens.wavelengths[lens.primary])
            o, d, _ = cr.launch(lens, field, wl)
            keep = np.r_[np.arange(0, len(o) - 1, 3), len(o) - 1]
            o, d = o[keep], d[keep]
            hits = {}
            for key, rule in (("optiland", shipped), ("optiland_projected_spacing",
                                                      projected_spacing)):
                DiffractiveInteractionModel.interact_real_rays = rule
                optic = build(name, lens)
                cr._strip_apertures(optic)
                cr.set_media(optic, lens, wl, [s.material_post for s in optic.surfaces.surfaces])
                p, ok, _, _ = cr.optiland_image(optic, o, d, wl, 1.0, np.zeros(3))
                assert ok.all(), (name, key)
                hits[key] = p
            DiffractiveInteractionModel.interact_real_rays = shipped
            pj, vj, _, _, _ = cr.jaxlens_image(unclipped(lens), o, d, wl)
            assert vj.all()
            for k in range(len(o)):
                rays.append({"field_deg": field.tolist(), "wavelength_um": wl,
                             "origin": o[k].tolist(), "direction": d[k].tolist(),
                             **{key: v[k].tolist() for key, v in hits.items()}})
            print(name, field, "max |jaxlens - optiland| mm:",
                  {key: float(np.max(np.abs(pj - v))) for key, v in hits.items()})
        optic = build(name, lens)
        out["files"][name] = {"optiland_f2": float(optic.paraxial.f2()), "rays": rays}
    write_whole(os.path.join(DATA, "reference.json"), json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
