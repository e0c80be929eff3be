"""Prints the round-40c agreement table: jaxlens against tests/data/acc40c_optiland.json
(tools/acc40c_reference.py), one row per lens and quantity, the worst field and wavelength.

    cd <repo> && python tools/acc40c_compare.py
"""

import json
import pathlib
import warnings

import jax
import numpy as np

jax.config.update("jax_enable_x64", True)

import jaxlens as jl  # noqa: E402
from jaxlens.analysis.wavefront_error import opd, wavefront  # noqa: E402
from jaxlens.imaging.psf import CoherentPSF, mtf, psf_info  # noqa: E402
from jaxlens.optics import paraxial  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
REF = json.loads((ROOT / "tests" / "data" / "acc40c_optiland.json").read_text())
FILES = {
    "tele_doublet_obna": "tests/data/zmx38a/tele_doublet_obna.zmx",
    "tele_triplet_floa": "tests/data/zmx38a/tele_triplet_floa.zmx",
    "tele_doublet_x20": "tests/data/acc40c/tele_doublet_x20.zmx",
    "virtual_singlet_angles": "tests/data/zmx_corpus7/virtual_singlet_angles.zmx",
    "virtual_stop_behind": "tests/data/zmx_corpus7/virtual_stop_behind.zmx",
    "virtual_stop_behind_aimed": "tests/data/zmx_corpus7/virtual_stop_behind_aimed.zmx",
    "plastic_curved_immersed_image": "tests/refcases_extra/plastic_curved_immersed_image.json",
}
POINTS = np.asarray(REF["settings"]["points"])


def row(lens, quantity, got, want):
    print(f"| {lens} | {quantity} | {got:.10g} | {want:.10g} | {abs(got - want):.2g} |")


def main():
    warnings.simplefilter("ignore")
    print("| lens | quantity | jaxlens | optiland | abs diff |")
    print("| --- | --- | --- | --- | --- |")
    for name, path in FILES.items():
        r = REF["lenses"][name]
        lens = jl.load(ROOT / path)
        aim = r.get("jaxlens_aim")
        pd = paraxial.paraxial_data(lens)
        row(name, "exit pupil z (mm)", float(pd.exit_pupil_z), r["exit_pupil"]["z"])
        worst = (0.0, 0.0, 0.0, "")
        for f, fr in zip(r["jaxlens_fields"], r["fields"], strict=True):
            for w, want in fr["opd"].items():
                got = np.asarray(opd(lens, f, POINTS, wavelength=float(w), aim=aim))
                k = int(np.argmax(np.abs(got - want)))
                d = abs(got[k] - want[k])
                if d >= worst[0]:
                    worst = (d, float(got[k]), float(want[k]), f"field {f}, {w} µm")
        row(name, f"OPD waves, worst of {len(POINTS)} points ({worst[3]})", worst[1], worst[2])
        f, fr = r["jaxlens_fields"][-1], r["fields"][-1]
        wf = wavefront(lens, f, grid=REF["settings"]["grid"], aim=aim)
        for key in ("rms", "pv", "rms_tilt_removed"):
            row(name, f"{key} waves, field {f}", float(getattr(wf, key)), fr["grid"][key])
        z = np.asarray(wf.zernike(terms=REF["settings"]["zernike_terms"]).coefficients)
        k = int(np.argmax(np.abs(z - fr["grid"]["noll"])))
        row(name, f"Noll Z{k + 1} waves (worst), field {f}", float(z[k]), fr["grid"]["noll"][k])
        if "mtf" not in fr:
            continue
        nu = r["mtf_freqs_cyc_per_mm"]
        _, t, _ = mtf(lens, f, wavelengths=[r["primary_um"]], frequencies=nu, diffraction=False)
        row(name, f"geometric MTF T at {nu[1]} c/mm, field {f}", float(t[1]),
            fr["mtf"]["tangential"][1])
        for f, fr in zip(r["jaxlens_fields"], r["fields"], strict=True):
            if "coherent_centre_strehl" in fr:
                info = psf_info(lens, f, wavelength=r["primary_um"], model=CoherentPSF(),
                                pixel_size=1e-4, kernel_size=3)
                k = np.asarray(info.psf)
                row(name, f"coherent Strehl at chief point, field {f}",
                    float(info.strehl) * k[1, 1] / k.max(), fr["coherent_centre_strehl"])


if __name__ == "__main__":
    main()
