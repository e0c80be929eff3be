# ruff: noqa: E501, E731
"""Round-34b bad-input probes: JSON lens files (keys that give one value twice, sections
read whole, field types, weights, round trips), image files (alpha, EXR channels, float32
range, bit depths, sRGB round trips, writes over a file) and the command lines' option
combinations (``classical``). The table of ``tools/probe_table.py`` (probe | outcome | what
happened).

Gaps found and fixed:
1. JSON lens: an aperture kind under two keys (``"EPD": 50`` beside ``aperture.epd`` 10,
   ``epd``/``EPD``, ``fnum``/``FNUM``/``f_number``) used the first and dropped the other,
   though the format says aperture keys must agree; ``primary`` beside
   ``primary_wavelength_nm`` (or ``_um`` beside ``_nm``) likewise. Refused unless they agree
   (one rule each in the new ``jaxlens/io/lens_system.py``, which holds the system sections
   moved out of ``lensfile.py``).
2. JSON lens: a key of ``units``, ``sensor``, ``object`` or ``fields`` that no one reads
   passed: ``"units": {"lengths": "in"}`` read inches as mm, ``"fields": {"unit": "rad"}``
   radians as degrees, ``"sensor": {"pixel_size_um": 9}`` beside ``pixel_size``. These
   sections are read whole: another key is refused (``lens_keys.closed``).
3. JSON lens: ``fields.type`` ``angle_deg_y`` with [θx, θy] pairs (or ``angle_deg_xy`` with
   single angles) was read by the values' shape: refused (``angle_deg``/``angle`` take
   either).
4. JSON lens: field or wavelength weights of another length than the fields (wavelengths)
   passed (equal ones without a warning); the ``.zmx`` reader refuses FWGN of another count.
5. ``write_png`` put alpha through the sRGB curve (0.5 written as code 188); now the colour
   channels only.
6. ``read_exr``'s default read a grey+alpha file (Y, A) as [A, Y]: now Y, alpha left out
   (as ``read_png`` drops it).
7. ``write_exr``/``write_psf_stack``: a value beyond float32 (1e300) was written as inf.
8. ``write_png``, ``write_exr``, ``write_psf_stack``, ``plot.save`` (every figure of
   ``report --plot``, ``classical``, ``tolerance``) and ``tolerance.json`` (``--overwrite``)
   wrote in place: a stop mid-write left a cut file where the earlier one was. Now a
   temporary file renamed into place (``json_values.whole_path``/``write_whole``).
9. ``classical --material-catalogs CDGM`` with the default ``--select-materials fixed``
   dropped the catalogs without a word: refused.

Before (branch base baf92e1, an archive) and after (branch audit34b), the same probes,
``PYTHONPATH=<tree> python tools/audit34b_probe.py`` from the tree's root, 61 probes, about
30 s each way:
    before: clear error: 19, crash: 5, ok: 13, silent wrong: 24
    after:  clear error: 40, ok: 21

A "Ctrl-C mid-write" row stops the write as its data reaches the disk (half a file written
in place, or before the rename of a whole write) and reads the earlier file back.

Probe (before -> after):
    lens EPD top 50 beside aperture.epd 10                                      silent wrong -> clear error
    lens aperture.epd 10 and aperture.EPD 50                                    silent wrong -> clear error
    lens aperture.fnum 4 and FNUM 8                                             silent wrong -> clear error
    lens aperture.fnum 4 and f_number 8                                         silent wrong -> clear error
    lens EPD top 10 beside aperture.epd 10 (control)                            ok           -> ok
    lens aperture.epd and fnum disagreeing (control: refused)                   clear error  -> clear error
    lens primary 0 beside primary_wavelength_nm 587.5618                        silent wrong -> clear error
    lens primary_wavelength_um beside _nm (disagreeing)                         silent wrong -> clear error
    lens primary 1 beside primary_wavelength_nm (control)                       ok           -> ok
    lens units {lengths: in}                                                    silent wrong -> clear error
    lens units {length_unit: in}                                                silent wrong -> clear error
    lens units {angles: rad}                                                    silent wrong -> clear error
    lens units {length: in} (control: refused)                                  clear error  -> clear error
    lens units {} (control)                                                     ok           -> ok
    lens sensor pixel_size_um beside pixel_size                                 silent wrong -> clear error
    lens sensor offset                                                          silent wrong -> clear error
    lens object {distance: inf, height}                                         silent wrong -> clear error
    lens fields {values, unit: rad}                                             silent wrong -> clear error
    lens fields type angle_deg_y with pairs                                     silent wrong -> clear error
    lens fields type angle_deg_xy with single angles                            silent wrong -> clear error
    lens fields type angle_deg with pairs (control)                             ok           -> ok
    lens fields.weights 2 for 3 fields                                          silent wrong -> clear error
    lens field_weights 5 for 3 fields                                           silent wrong -> clear error
    lens wavelength_weights 2 for 3                                             silent wrong -> clear error
    lens key given twice (control: refused)                                     clear error  -> clear error
    lens thickness 1e400 (inf)                                                  clear error  -> clear error
    lens radius -0.0                                                            clear error  -> clear error
    lens stop_surface_index 99                                                  clear error  -> clear error
    lens stop_surface_index 2.0                                                 clear error  -> clear error
    lens surfaces [object, image] only                                          clear error  -> clear error
    lens sensor pixel_size 5 (µm in mm)                                        clear error  -> clear error
    lens sensor resolution [4, 4, 3]                                            clear error  -> clear error
    lens fields ['0', '10', '20'] (numbers as strings; control)                 ok           -> ok
    lens load/save/load of the shipped lenses (control: exact)                  ok           -> ok
    write_png RGBA alpha 0.5 (code 128?)                                        silent wrong -> ok
    write_png grey+alpha alpha 0.5 (code 128?)                                  silent wrong -> ok
    write_png RGB 0.5 (control: sRGB code 188)                                  ok           -> ok
    read_exr Y+A (default channels)                                             silent wrong -> ok
    read_exr RGBA (control: RGB)                                                ok           -> ok
    write_exr 1e300 (beyond float32)                                            silent wrong -> clear error
    write_psf_stack 1e300                                                       silent wrong -> clear error
    write_exr NaN (control: refused)                                            clear error  -> clear error
    write_png 1x1 (control)                                                     ok           -> ok
    write_png .jpg (control: refused)                                           clear error  -> clear error
    read_png 2-bit grey (control)                                               ok           -> ok
    png 16-bit sRGB round trip (control: 2e-5)                                  ok           -> ok
    write_png over a file, Ctrl-C mid-write (then read)                         crash        -> ok
    write_exr over a file, Ctrl-C mid-write (then read)                         crash        -> ok
    write_psf_stack over a file, Ctrl-C mid-write (then read)                   crash        -> ok
    plot.save over a figure, Ctrl-C mid-write (then read)                       crash        -> ok
    tolerance write_report --overwrite, Ctrl-C mid-write                        crash        -> ok
    classical --material-catalogs CDGM (fixed materials)                        silent wrong -> clear error
    classical --material-catalogs CDGM --select-materials continuous (control)  ok           -> ok
    classical --seeds 4 --seed-list 1,2                                         clear error  -> clear error
    classical --polish none --polish-steps 50                                   clear error  -> clear error
    classical --ablation-out without --ablation                                 clear error  -> clear error
    classical --population 4 (control: any recipe)                              ok           -> ok
    classical --tolerance-threshold 1e9                                         clear error  -> clear error
    classical --bfl 1e6                                                         clear error  -> clear error
    classical --fov-start 100 (above --fov)                                     clear error  -> clear error
    classical --polish-steps 10**9                                              clear error  -> clear error
"""

import json
import os
import pathlib
import sys
import warnings

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
warnings.simplefilter("ignore")

import numpy as np  # noqa: E402
from probe_table import COOKE, ROOT, TMP, CutWriter, checked, cli, fresh, patched, probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402


# ----------------------------------------------------------------------------- JSON lens files
def lens_files():
    base = json.loads(pathlib.Path(COOKE).read_text())

    def lf(edit=None, text=None):
        d = json.loads(json.dumps(base))
        if edit:
            edit(d)
        p = os.path.join(fresh("l"), "lens.json")
        pathlib.Path(p).write_text(text if text is not None else json.dumps(d))

        def go():
            lens = jl.load(p)
            return (f"epd {float(lens.epd):.6g}, primary {lens.primary}, fields "
                    f"{np.asarray(lens.fields).tolist()}")
        return go
    probe("lens EPD top 50 beside aperture.epd 10", lf(lambda d: d.update(EPD=50.0)), "EPD 50", "aperture.epd 10", "disagree")
    probe("lens aperture.epd 10 and aperture.EPD 50", lf(lambda d: d["aperture"].update(EPD=50.0)), "aperture.EPD 50", "disagree")
    probe("lens aperture.fnum 4 and FNUM 8", lf(lambda d: d.update(aperture={"fnum": 4, "FNUM": 8})), "FNUM 8", "disagree")
    probe("lens aperture.fnum 4 and f_number 8", lf(lambda d: d.update(aperture={"fnum": 4, "f_number": 8})), "f_number 8", "disagree")
    probe("lens EPD top 10 beside aperture.epd 10 (control)", lf(lambda d: d.update(EPD=10.0)), good=True)
    probe("lens aperture.epd and fnum disagreeing (control: refused)", lf(lambda d: d.update(aperture={"epd": 10, "fnum": 2})), "disagree")
    probe("lens primary 0 beside primary_wavelength_nm 587.5618", lf(lambda d: d.update(primary=0)), "primary 0", "primary_wavelength_nm", "disagree")
    probe("lens primary_wavelength_um beside _nm (disagreeing)", lf(lambda d: d.update(primary_wavelength_um=0.4861327)), "primary_wavelength_um", "disagree")
    probe("lens primary 1 beside primary_wavelength_nm (control)", lf(lambda d: d.update(primary=1)), good=True)
    probe("lens units {lengths: in}", lf(lambda d: d.update(units={"lengths": "in"})), "units", "lengths")
    probe("lens units {length_unit: in}", lf(lambda d: d.update(units={"length_unit": "in"})), "units", "length_unit")
    probe("lens units {angles: rad}", lf(lambda d: d.update(units={"angles": "rad"})), "units", "angles")
    probe("lens units {length: in} (control: refused)", lf(lambda d: d.update(units={"length": "in"})), "units.length")
    probe("lens units {} (control)", lf(lambda d: d.update(units={})), good=True)
    probe("lens sensor pixel_size_um beside pixel_size", lf(lambda d: d.update(sensor={"resolution": [8, 8], "pixel_size": 0.005, "pixel_size_um": 9})), "sensor", "pixel_size_um")
    probe("lens sensor offset", lf(lambda d: d.update(sensor={"resolution": [8, 8], "pixel_size": 0.005, "offset": [1, 2]})), "sensor", "offset")
    probe("lens object {distance: inf, height}", lf(lambda d: d.update(object={"distance": "inf", "height": 5})), "object", "height")
    probe("lens fields {values, unit: rad}", lf(lambda d: d.update(fields={"values": [0, 14, 20], "unit": "rad"})), "fields", "unit")
    probe("lens fields type angle_deg_y with pairs", lf(lambda d: d.update(fields={"type": "angle_deg_y", "values": [[0, 0], [0, 10]]})), "angle_deg_y", "pairs")
    probe("lens fields type angle_deg_xy with single angles", lf(lambda d: d.update(fields={"type": "angle_deg_xy", "values": [0, 10]})), "angle_deg_xy", "single")
    probe("lens fields type angle_deg with pairs (control)", lf(lambda d: d.update(fields={"type": "angle_deg", "values": [[0, 0], [0, 10]]})), good=True)
    probe("lens fields.weights 2 for 3 fields", lf(lambda d: d["fields"].update(weights=[1, 1])), "fields.weights", "(3)")
    probe("lens field_weights 5 for 3 fields", lf(lambda d: d.update(field_weights=[1] * 5)), "field_weights", "(3)")
    probe("lens wavelength_weights 2 for 3", lf(lambda d: d.update(wavelength_weights=[1, 1])), "wavelength_weights", "(3)")
    s = json.dumps(base)
    probe("lens key given twice (control: refused)", lf(text=s[:-1] + ', "name": "x"}'), "twice")
    th = json.dumps(base["surfaces"][1]["thickness"])
    probe("lens thickness 1e400 (inf)", lf(text=s.replace(f'"thickness": {th}', '"thickness": 1e400', 1)), "thickness")
    probe("lens radius -0.0", lf(lambda d: d["surfaces"][2].update(radius=-0.0)), "radius")
    probe("lens stop_surface_index 99", lf(lambda d: d.update(stop_surface_index=99)), "stop_surface_index 99")
    probe("lens stop_surface_index 2.0", lf(lambda d: d.update(stop_surface_index=2.0)), "stop_surface_index")
    probe("lens surfaces [object, image] only", lf(lambda d: d.update(surfaces=[d["surfaces"][0], d["surfaces"][-1]])), "no lens surfaces")
    probe("lens sensor pixel_size 5 (µm in mm)", lf(lambda d: d.update(sensor={"resolution": [480, 640], "pixel_size": 5})), "pixel_size")
    probe("lens sensor resolution [4, 4, 3]", lf(lambda d: d.update(sensor={"resolution": [4, 4, 3], "pixel_size": 0.005})), "sensor")
    probe("lens fields ['0', '10', '20'] (numbers as strings; control)", lf(lambda d: d["fields"].update(values=["0", "10", "20"])), good=True)

    def round_trip():
        import glob

        import jax
        n = 0
        for src in sorted(glob.glob(os.path.join(ROOT, "jaxlens", "data", "lenses", "*.json"))):
            a = jl.load(src)
            p, q = os.path.join(TMP, "rt_a.json"), os.path.join(TMP, "rt_b.json")
            jl.save(a, p)
            b = jl.load(p)
            jl.save(b, q)
            la, ta = jax.tree_util.tree_flatten(a)
            lb, tb = jax.tree_util.tree_flatten(b)
            if ta != tb or pathlib.Path(p).read_text() != pathlib.Path(q).read_text() or not all(
                    np.array_equal(np.asarray(x), np.asarray(y)) for x, y in zip(la, lb, strict=True)):
                raise RuntimeError(f"{os.path.basename(src)} changed in a round trip")
            n += 1
        return f"{n} lenses the same"
    probe("lens load/save/load of the shipped lenses (control: exact)", round_trip, good=True)


# ----------------------------------------------------------------------------- images
def images():
    import struct
    import zlib

    from PIL import Image

    from jaxlens.io import images as IM

    d = fresh("img")

    def alpha(img):
        def go():
            p = os.path.join(d, f"c{len(os.listdir(d))}.png")
            IM.write_png(p, img)
            codes = np.asarray(Image.open(p))[0, 0].tolist()
            return codes[-1] == 128, f"codes {codes} (alpha 0.5 is code 128)"
        return go
    checked("write_png RGBA alpha 0.5 (code 128?)", alpha(np.full((2, 2, 4), 0.5)))
    checked("write_png grey+alpha alpha 0.5 (code 128?)", alpha(np.full((2, 2, 2), 0.5)))
    probe("write_png RGB 0.5 (control: sRGB code 188)", lambda: (IM.write_png(os.path.join(d, "rgb.png"), np.full((2, 2, 3), 0.5)), np.asarray(Image.open(os.path.join(d, "rgb.png")))[0, 0].tolist())[1], good=True)
    IM.write_exr(os.path.join(d, "ya.exr"), np.dstack([np.full((2, 2), 0.25), np.ones((2, 2))]), channels=("Y", "A"))

    def ya():
        a = IM.read_exr(os.path.join(d, "ya.exr"))
        return a.shape == (2, 2) and bool(np.all(a == 0.25)), f"shape {a.shape}, first pixel {a[0, 0].tolist()} (Y 0.25, A 1)"
    checked("read_exr Y+A (default channels)", ya)
    IM.write_exr(os.path.join(d, "rgba.exr"), np.ones((2, 2, 4)), channels=("R", "G", "B", "A"))
    probe("read_exr RGBA (control: RGB)", lambda: IM.read_exr(os.path.join(d, "rgba.exr")).shape, good=True)

    def huge():
        p = os.path.join(d, "huge.exr")
        with np.errstate(all="ignore"):
            IM.write_exr(p, np.full((2, 2), 1e300))
        return IM.read_exr(p)
    probe("write_exr 1e300 (beyond float32)", huge, "float32")

    def huge_psf():
        p = os.path.join(d, "psf.exr")
        with np.errstate(all="ignore"):
            IM.write_psf_stack(p, np.full((1, 3, 3), 1e300))
        return IM.read_psf_stack(p)[0].max()
    probe("write_psf_stack 1e300", huge_psf, "float32")
    probe("write_exr NaN (control: refused)", lambda: IM.write_exr(os.path.join(d, "n.exr"), np.full((2, 2), np.nan)), "finite")
    probe("write_png 1x1 (control)", lambda: (IM.write_png(os.path.join(d, "o.png"), np.full((1, 1, 3), 0.5)), IM.read_png(os.path.join(d, "o.png")).shape)[1], good=True)
    probe("write_png .jpg (control: refused)", lambda: IM.write_png(os.path.join(d, "x.jpg"), np.zeros((2, 2))), ".png")

    def chunk(tag, payload):
        return struct.pack(">I", len(payload)) + tag + payload + struct.pack(">I", zlib.crc32(tag + payload) & 0xFFFFFFFF)
    g2 = os.path.join(d, "g2.png")
    rows = b"\x00" + bytes([0b00110000]) + b"\x00" + bytes([0b10110000])  # 2-bit grey: 0 3 / 2 3
    pathlib.Path(g2).write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 2, 2, 2, 0, 0, 0, 0)) + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))
    checked("read_png 2-bit grey (control)", lambda: (lambda v: (v == [0.0, 1.0, 0.6667, 1.0], str(v)))(IM.read_png(g2, linear=False).astype(float).ravel().round(4).tolist()))

    def rt16():
        x = np.linspace(0, 1, 1001).reshape(1, -1)
        IM.write_png(os.path.join(d, "r16.png"), x, bits=16)
        err = float(np.abs(IM.read_png(os.path.join(d, "r16.png")) - x).max())
        return err < 5e-5, f"max error {err:.2g}"
    checked("png 16-bit sRGB round trip (control: 2e-5)", rt16)


# ----------------------------------------------------------------------------- writes over a file
def whole_writes():
    from jaxlens import plot
    from jaxlens.experiments import tolerance as TOL
    from jaxlens.io import images as IM

    fig = plot.plot_layout(jl.load(COOKE))

    def stopped(name, write):
        """``write`` over an earlier file, stopped (Ctrl-C) as its data reaches the disk:
        half written in place, or before the rename of a whole write; then the file read
        back (the earlier one, or a cut one: lost)."""
        def go():
            folder = fresh("whole")
            path = os.path.join(folder, name)
            pathlib.Path(path).write_bytes(b"the earlier file")
            real_replace, real_wb, real_savefig = os.replace, pathlib.Path.write_bytes, type(fig).savefig

            def cut(*a, **k):
                raise KeyboardInterrupt

            def half(self, data):
                real_wb(self, data[: len(data) // 2])
                raise KeyboardInterrupt

            def half_fig(self, fname, **k):
                pathlib.Path(fname).write_bytes(b"\x89PNG half")
                raise KeyboardInterrupt
            os.replace, pathlib.Path.write_bytes, type(fig).savefig = cut, half, half_fig
            try:
                write(path)
            except KeyboardInterrupt:
                pass
            finally:
                os.replace, pathlib.Path.write_bytes, type(fig).savefig = real_replace, real_wb, real_savefig
            left = sorted(os.listdir(folder))
            if pathlib.Path(path).read_bytes() != b"the earlier file":
                raise RuntimeError(f"the earlier {name} is lost (cut or replaced mid-write)")
            if left != [name]:
                raise RuntimeError(f"partial files left: {left}")
            return "the earlier file, intact"
        return go

    def exr_cut(write):
        """OpenEXR writes in C: its write is stopped by making the library's write raise
        after a half file is on the disk."""
        import OpenEXR

        def go_write(path):
            real = OpenEXR.File.write

            def half(self, fname):
                real(self, fname)
                data = pathlib.Path(fname).read_bytes()
                with open(fname, "r+b") as f:  # cut to half, as a stop mid-write leaves it
                    f.truncate(len(data) // 2)
                raise KeyboardInterrupt
            OpenEXR.File.write = half
            try:
                write(path)
            finally:
                OpenEXR.File.write = real
        return go_write
    probe("write_png over a file, Ctrl-C mid-write (then read)", stopped("a.png", lambda p: IM.write_png(p, np.full((64, 64), 0.5))), good=True)
    probe("write_exr over a file, Ctrl-C mid-write (then read)", stopped("a.exr", exr_cut(lambda p: IM.write_exr(p, np.full((64, 64), 0.5)))), good=True)
    probe("write_psf_stack over a file, Ctrl-C mid-write (then read)", stopped("p.exr", exr_cut(lambda p: IM.write_psf_stack(p, np.full((2, 9, 9), 0.5)))), good=True)
    probe("plot.save over a figure, Ctrl-C mid-write (then read)", stopped("fig.png", lambda p: plot.save(fig, p)), good=True)

    def tol_write(path):
        import builtins
        real_open = builtins.open

        TOL.open = lambda p, mode="r", *a, **k: CutWriter(real_open(p, mode, *a, **k)) if "w" in mode else real_open(p, mode, *a, **k)
        try:
            TOL.write_report({"command": "x", "trials": list(range(1000))}, os.path.dirname(path), plots=False)
        finally:
            del TOL.open
    probe("tolerance write_report --overwrite, Ctrl-C mid-write", stopped("tolerance.json", tol_write), good=True)


# ----------------------------------------------------------------------------- command lines
def classical_cli():
    from jaxlens.experiments import classical as C

    c = lambda *a: cli(patched(C, ["run_design", "run_ablation"], lambda: C.main(["--out", os.path.join(TMP, f"c{len(os.listdir(TMP))}"), *a])))
    probe("classical --material-catalogs CDGM (fixed materials)", c("--material-catalogs", "CDGM"), "--material-catalogs", "ignored")
    probe("classical --material-catalogs CDGM --select-materials continuous (control)", c("--material-catalogs", "CDGM", "--select-materials", "continuous"), good=True)
    probe("classical --seeds 4 --seed-list 1,2", c("--seeds", "4", "--seed-list", "1,2"), "--seeds")
    probe("classical --polish none --polish-steps 50", c("--polish", "none", "--polish-steps", "50"), "--polish-steps")
    probe("classical --ablation-out without --ablation", c("--ablation-out", os.path.join(TMP, "abx")), "--ablation-out")
    probe("classical --population 4 (control: any recipe)", c("--population", "4"), good=True)
    probe("classical --tolerance-threshold 1e9", c("--tolerance-threshold", "1e9"), "--tolerance-threshold")
    probe("classical --bfl 1e6", c("--bfl", "1e6"), "--bfl")
    probe("classical --fov-start 100 (above --fov)", c("--fov-start", "100"), "--fov-start")
    probe("classical --polish-steps 10**9", c("--polish-steps", str(10**9)), "--polish-steps")


if __name__ == "__main__":
    run([lens_files, images, whole_writes, classical_cli])
