# ruff: noqa: E501, E731
"""Round-33b bad-input probes: the file readers (``.zmx`` headers and pickups, side AGF
catalogs, file encodings, AGF records jaxlens skips), the ``report`` options that only a
``.zmx`` reads, and the results files the benchmarks and tools write. The table of
``tools/probe_table.py`` (probe | outcome | what happened).

Gaps found and fixed:
1. ``.zmx``: GCAT, ENVD, RAIM, MNUM, FWGN, FWGT, WWGT or WWGN given twice, and PZUP (PPAR n)
   twice in one surface: the later line replaced the earlier without a word. Refused,
   naming both lines (one rule: ``zmx_parse._repeat``). FWGT beside FWGN, as Zemax 2006
   writes them, still reads.
2. ``.zmx`` pickups (PZUP, PPAR n, a CURV pickup solve) of a surface the file lacks, of
   their own surface, or of a later surface whose same value is itself a pickup (solved
   after it: a stale value) were read without a word; a configuration re-solving one read
   the stale value. Refused with the line (``zmx_config.check_pickups``).
3. A side ``.AGF`` catalog holding a glass the lens uses in two cases (OKP4 and okp4): the
   later record was used (the AGF reader only warned). Refused, naming both records.
4. A ``.zmx`` or ``.agf`` with a UTF-32 BOM: LE was decoded as UTF-16 LE (a NUL after every
   character: "not a Zemax keyword line"), BE was "binary data". Read (BOMs longest first,
   in the one decoder ``decode_zemax_text``).
5. AGF ``TD`` (also ``ED``, ``IT``) records of text were skipped: refused with the line.
6. ``report LENS.json --unknown-glass error`` dropped the option; ``model`` and
   ``--config 1`` were refused naming the load function's ``unknown_glass=``/``config=``;
   ``--list-configs --unknown-glass model`` listed. One check names the option.
7. Results written in place (``benchmarks.common.write_json`` and the other benchmarks,
   ``tools/export_reevaluation.py --json``, the reference tools): a stop mid-write left a
   cut file. Now ``json_values.write_whole`` (a temporary file renamed).

Before (branch base 72310e1, an archive) and after (branch audit33b), the same probes,
``PYTHONPATH=<tree> python tools/audit33b_probe.py`` from the tree's root, 53 probes,
about a minute each way:
    before: clear error: 2, crash: 4, ok: 15, silent wrong: 30, vague error: 2
    after:  clear error: 34, ok: 19

A "Ctrl-C mid-write" row stops the write as its data reaches the disk (half a file written
in place, or before the rename of a whole write) and reads the file back. The last row
scans the writers' source for in-place writes (``write_text``, ``json.dump``, ``open(…,
"w")``, ``np.savez``) not marked as into a temporary folder or memory.

Probe (before -> after):
    zmx GCAT given twice                                                                     silent wrong -> clear error
    zmx ENVD given twice (30 C the second)                                                   silent wrong -> clear error
    zmx RAIM given twice                                                                     silent wrong -> clear error
    zmx MNUM given twice                                                                     silent wrong -> clear error
    zmx FWGN given twice (unequal the second)                                                silent wrong -> clear error
    zmx FWGT given twice                                                                     silent wrong -> clear error
    zmx WWGT given twice                                                                     silent wrong -> clear error
    zmx WWGN given twice                                                                     silent wrong -> clear error
    zmx FWGT beside FWGN, WWGT beside WWGN (control: Zemax 2006)                             ok           -> ok
    zmx VERS given twice (control: harmless)                                                 ok           -> ok
    zmx PZUP given twice in a surface                                                        silent wrong -> clear error
    zmx PPAR 3 given twice in a surface                                                      silent wrong -> clear error
    zmx PPAR 1 and PPAR 3 in a surface (control)                                             ok           -> ok
    zmx PZUP of surface 40 (a 14-surface file)                                               silent wrong -> clear error
    zmx PZUP of its own surface                                                              silent wrong -> clear error
    zmx PZUP of a later surface's PZUP (stale)                                               silent wrong -> clear error
    zmx CURV pickup of a later surface's pickup (stale)                                      silent wrong -> clear error
    zmx CURV pickup of its own surface                                                       silent wrong -> clear error
    zmx CURV pickup of surface 99                                                            silent wrong -> clear error
    zmx PPAR 3 of surface 99                                                                 silent wrong -> clear error
    zmx PPAR 3 of its own surface                                                            silent wrong -> clear error
    zmx PPAR 3 of a later surface's PPAR 3 (stale)                                           silent wrong -> clear error
    zmx PPAR 3 of a later plain surface (control)                                            ok           -> ok
    zmx config 2: PZUP of surface 40                                                         silent wrong -> clear error
    zmx config 2: PZUP of the later surface 11's PZUP (stale)                                silent wrong -> clear error
    zmx config 2: the pickups re-solved (control)                                            ok           -> ok
    zmx the corpus's pickups (control: earlier surfaces)                                     ok           -> ok
    side AGF: OKP4 and okp4, the lens uses OKP4                                              silent wrong -> clear error
    side AGF: XYZ1 and xyz1, unused (control)                                                ok           -> ok
    side AGF: OKP4 twice in one case (control: documented, the later wins)                   ok           -> ok
    zmx and side AGF in UTF-32 LE with a BOM                                                 crash        -> ok
    zmx and side AGF in UTF-32 BE with a BOM                                                 crash        -> ok
    zmx and side AGF in UTF-16 LE with a BOM (control)                                       ok           -> ok
    zmx in UTF-8 with a BOM (control)                                                        ok           -> ok
    agf TD 0 0 abc 0 0 0 20                                                                  silent wrong -> clear error
    agf TD ... 2O (letter O in Tref)                                                         silent wrong -> clear error
    agf TD with a comma decimal                                                              silent wrong -> clear error
    agf ED 0 0 O 0 0 (letter O)                                                              silent wrong -> clear error
    agf IT 0.4 x 10                                                                          silent wrong -> clear error
    agf TD as written (control)                                                              ok           -> ok
    agf TD 1e-6 (exponent; control)                                                          ok           -> ok
    report LENS.json --unknown-glass model                                                   vague error  -> clear error
    report LENS.json --unknown-glass error (dropped?)                                        silent wrong -> clear error
    report LENS.json --config 1                                                              vague error  -> clear error
    report LENS.json --config 0                                                              clear error  -> clear error
    report LENS.json --lenient                                                               clear error  -> clear error
    report LENS.zmx --list-configs --unknown-glass model                                     silent wrong -> clear error
    report LENS.zmx --list-configs --lenient                                                 silent wrong -> clear error
    report LENS.zmx --unknown-glass model (control)                                          ok           -> ok
    report LENS.zmx --list-configs (control)                                                 ok           -> ok
    benchmarks write_json over a result, Ctrl-C mid-write (then read)                        crash        -> ok
    json_values.write_whole over a file, Ctrl-C before the rename (control)                  ok           -> ok
    results writers writing in place (benchmarks, tools/*_reference.py, export_reevaluation) crash        -> ok
"""

import json
import os
import pathlib
import sys
import warnings

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
warnings.simplefilter("ignore")

import numpy as np  # noqa: E402
from probe_table import COOKE, ROOT, SEED0, cli, fresh, probe, run  # noqa: E402

import jaxlens as jl  # noqa: E402

DATA = os.path.join(ROOT, "tests", "data", "zmx")
PPAR_FILE = os.path.join(DATA, "rayoptics_HoO-V2C18Ex46.zmx")
PZUP_FILE = os.path.join(DATA, "rayoptics_US00583336-2-scaled.zmx")
PIVOTED = os.path.join(DATA, "zemax2006", "kraken_pivoted_lens.ZMX")
PLASTICS = os.path.join(ROOT, "experiments", "classical", "designs", "PLASTICS.AGF")




def edited(src, old, new, *more, **load):
    """``src`` with ``old`` replaced by ``new`` (and each further (old, new) pair in
    ``more``), loaded: its total thickness, a number to show."""
    text = pathlib.Path(src).read_text(encoding="utf-8", errors="replace")
    for a, b in ((old, new), *more):
        assert a in text, a
        text = text.replace(a, b, 1)
    p = os.path.join(fresh("z"), os.path.basename(src))
    pathlib.Path(p).write_text(text, encoding="utf-8")
    return lambda: round(float(np.sum(jl.load(p, **load).thickness)), 6)


def top_index(path):
    """The highest index at 0.55 µm of a lens's materials (OKP4's in seed_0)."""
    return round(max(float(np.max(m.index(0.55))) for m in jl.load(path).materials), 6)


def seed0_plus(after, extra):
    """seed_0.zmx with ``extra`` lines after its first line starting ``after``."""
    lines = pathlib.Path(SEED0).read_text().splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.strip().startswith(after))
    return edited(SEED0, lines[i] + "\n", lines[i] + "\n" + extra + "\n")


# ----------------------------------------------------------------------------- zmx headers
def zmx_headers():
    probe("zmx GCAT given twice", seed0_plus("FWGN", "GCAT SCHOTT"), "GCAT given twice", "line")
    probe("zmx ENVD given twice (30 C the second)", seed0_plus("FWGN", "ENVD 3.0E+1 1 0"), "ENVD given twice")
    probe("zmx RAIM given twice", seed0_plus("FWGN", "RAIM 0 0 1 1 0 0 0 0 0 1\nRAIM 0 0 0 1 0 0 0 0 0 1"), "RAIM given twice")
    probe("zmx MNUM given twice", seed0_plus("FWGN", "MNUM 1 1\nMNUM 2 1"), "MNUM given twice")
    probe("zmx FWGN given twice (unequal the second)", seed0_plus("FWGN", "FWGN 1 1 1 1 2"), "FWGN given twice")
    probe("zmx FWGT given twice", seed0_plus("FWGN", "FWGT 1 1 1 1 1\nFWGT 1 1 1 1 2"), "FWGT given twice")
    probe("zmx WWGT given twice", seed0_plus("FWGN", "WWGT 1 1 1\nWWGT 1 2 1"), "WWGT given twice")
    probe("zmx WWGN given twice", seed0_plus("FWGN", "WWGN 1 1 1\nWWGN 1 2 1"), "WWGN given twice")
    probe("zmx FWGT beside FWGN, WWGT beside WWGN (control: Zemax 2006)", lambda: len(jl.load(PIVOTED).surfaces), good=True)
    probe("zmx VERS given twice (control: harmless)", seed0_plus("VERS", "VERS 190513 80 123457 L123457"), good=True)
    probe("zmx PZUP given twice in a surface", edited(PZUP_FILE, "PZUP 6.0 1 0 0", "PZUP 6.0 1 0 0\n  PZUP 5.0 1 0 0"), "PZUP given twice in surface 7")
    probe("zmx PPAR 3 given twice in a surface", edited(PPAR_FILE, "PPAR 3 2 1.0", "PPAR 3 3 1.0 0 0\n  PPAR 3 2 1.0"), "PPAR 3 given twice in surface 4")
    probe("zmx PPAR 1 and PPAR 3 in a surface (control)", edited(PPAR_FILE, "PPAR 3 2 1.0", "PPAR 1 2 1.0 0 0\n  PPAR 3 2 1.0"), good=True)


# ----------------------------------------------------------------------------- zmx pickups
def zmx_pickups():
    probe("zmx PZUP of surface 40 (a 14-surface file)", edited(PZUP_FILE, "PZUP 6.0 1 0 0", "PZUP 40 1 0 0"), "surface 40", "does not have")
    probe("zmx PZUP of its own surface", edited(PZUP_FILE, "PZUP 6.0 1 0 0", "PZUP 7 1 0 0"), "own surface")
    probe("zmx PZUP of a later surface's PZUP (stale)", edited(PZUP_FILE, "PZUP 6.0 1 0 0", "PZUP 8 1 0 0"), "not yet solved", "line")
    probe("zmx CURV pickup of a later surface's pickup (stale)", edited(PZUP_FILE, "4 6.0 -1. 0", "4 9.0 -1. 0"), "curvature pickup", "not yet solved")
    probe("zmx CURV pickup of its own surface", edited(PZUP_FILE, "4 6.0 -1. 0", "4 8 -1. 0"), "own surface")
    probe("zmx CURV pickup of surface 99", edited(PZUP_FILE, "4 6.0 -1. 0", "4 99 -1. 0"), "surface 99")
    probe("zmx PPAR 3 of surface 99", edited(PPAR_FILE, "PPAR 3 2 1.0", "PPAR 3 99 1.0"), "surface 99")
    probe("zmx PPAR 3 of its own surface", edited(PPAR_FILE, "PPAR 3 2 1.0", "PPAR 3 4 1.0"), "own surface")
    probe("zmx PPAR 3 of a later surface's PPAR 3 (stale)", edited(PPAR_FILE, "PPAR 3 2 1.0", "PPAR 3 8 1.0"), "PARM 3", "not yet solved")
    probe("zmx PPAR 3 of a later plain surface (control)", edited(PPAR_FILE, "PPAR 3 2 1.0", "PPAR 3 6 1.0"), good=True)
    # Two configurations, the second changing surface 2's thickness (1.386): surface 11's
    # PZUP (of surface 2) is solved again.
    two = ("MNUM 1 1", "MNUM 2 1\nTHIC 2 1 1.386\nTHIC 2 2 2.386")
    probe("zmx config 2: PZUP of surface 40", edited(PZUP_FILE, "PZUP 6.0 1 0 0", "PZUP 40 1 0 0", two, config=2), "surface 40")
    probe("zmx config 2: PZUP of the later surface 11's PZUP (stale)", edited(PZUP_FILE, "PZUP 3.0 1 0 0", "PZUP 11 1 0 0", two, config=2), "not yet solved")
    probe("zmx config 2: the pickups re-solved (control)", edited(PZUP_FILE, "MNUM 1 1", two[1], config=2), good=True)
    probe("zmx the corpus's pickups (control: earlier surfaces)", lambda: [len(jl.load(p).surfaces) for p in (PZUP_FILE, PPAR_FILE, PIVOTED)], good=True)


# ----------------------------------------------------------------------------- side AGF, encodings
def glass_files():
    agf = pathlib.Path(PLASTICS).read_text()
    okp4 = agf[agf.index("NM OKP4"):]

    def beside(extra):
        d = fresh("side")
        pathlib.Path(d, "seed_0.zmx").write_text(pathlib.Path(SEED0).read_text())
        pathlib.Path(d, "PLASTICS.AGF").write_text(agf + extra)
        return lambda: top_index(os.path.join(d, "seed_0.zmx"))
    probe("side AGF: OKP4 and okp4, the lens uses OKP4", beside(okp4.replace("NM OKP4 1 607270 1.607", "NM okp4 1 6072 1.6072").replace("2.4740105971476036E+000", "2.4745E+000")), "two cases", "okp4")
    probe("side AGF: XYZ1 and xyz1, unused (control)", beside(okp4.replace("NM OKP4", "NM XYZ1") + okp4.replace("NM OKP4", "NM xyz1")), good=True)
    probe("side AGF: OKP4 twice in one case (control: documented, the later wins)", beside(okp4), good=True)
    text = pathlib.Path(SEED0).read_text()

    def encoded(codec, bom, name="seed_0.zmx"):
        d = fresh("enc")
        pathlib.Path(d, name).write_bytes(bom + text.encode(codec))
        pathlib.Path(d, "PLASTICS.AGF").write_bytes(bom + agf.encode(codec))
        return lambda: top_index(os.path.join(d, name))
    probe("zmx and side AGF in UTF-32 LE with a BOM", encoded("utf-32-le", b"\xff\xfe\x00\x00"), good=True)
    probe("zmx and side AGF in UTF-32 BE with a BOM", encoded("utf-32-be", b"\x00\x00\xfe\xff"), good=True)
    probe("zmx and side AGF in UTF-16 LE with a BOM (control)", encoded("utf-16-le", b"\xff\xfe"), good=True)
    probe("zmx in UTF-8 with a BOM (control)", encoded("utf-8", b"\xef\xbb\xbf"), good=True)

    def agf_record(old, new):
        from jaxlens.optics import catalog as CAT
        bad = agf.replace(old, new, 1) if old else agf + new + "\n"
        p = os.path.join(fresh("agf"), "P.AGF")
        pathlib.Path(p).write_text(bad)
        return lambda: float(CAT.load_agf(p)["OKP4"].index(0.55))
    probe("agf TD 0 0 abc 0 0 0 20", agf_record("TD 0 0 0 0 0 0 20", "TD 0 0 abc 0 0 0 20"), "P.AGF:5", "TD")
    probe("agf TD ... 2O (letter O in Tref)", agf_record("TD 0 0 0 0 0 0 20", "TD 0 0 0 0 0 0 2O"), "P.AGF:5", "TD")
    probe("agf TD with a comma decimal", agf_record("TD 0 0 0 0 0 0 20", "TD 0 0 0 0,5 0 0 20"), "P.AGF:5", "TD")
    probe("agf ED 0 0 O 0 0 (letter O)", agf_record("ED 0 0 0 0 0", "ED 0 0 O 0 0"), "P.AGF:3", "ED")
    probe("agf IT 0.4 x 10", agf_record("", "IT 0.4 x 10"), "P.AGF:7", "IT")
    probe("agf TD as written (control)", agf_record("", ""), good=True)
    probe("agf TD 1e-6 (exponent; control)", agf_record("TD 0 0 0 0 0 0 20", "TD 1e-6 0 0 0 0 0 20"), good=True)


# ----------------------------------------------------------------------------- report options
def report_options():
    from jaxlens.__main__ import main

    rep = lambda *a: cli(lambda: main(["report", *map(str, a)]))
    probe("report LENS.json --unknown-glass model", rep(COOKE, "--unknown-glass", "model"), "--unknown-glass", ".zmx lens only")
    probe("report LENS.json --unknown-glass error (dropped?)", rep(COOKE, "--unknown-glass", "error"), "--unknown-glass", ".zmx lens only")
    probe("report LENS.json --config 1", rep(COOKE, "--config", "1"), "--config", ".zmx lens only")
    probe("report LENS.json --config 0", rep(COOKE, "--config", "0"), "--config")
    probe("report LENS.json --lenient", rep(COOKE, "--lenient"), "--lenient")
    probe("report LENS.zmx --list-configs --unknown-glass model", rep(SEED0, "--list-configs", "--unknown-glass", "model"), "--unknown-glass", "ignored")
    probe("report LENS.zmx --list-configs --lenient", rep(SEED0, "--list-configs", "--lenient"), "--lenient", "ignored")
    probe("report LENS.zmx --unknown-glass model (control)", rep(SEED0, "--unknown-glass", "model"), good=True)
    probe("report LENS.zmx --list-configs (control)", rep(SEED0, "--list-configs"), good=True)


# ----------------------------------------------------------------------------- results written whole
def results_files():
    import pathlib as P

    from jaxlens.io import json_values

    def stopped(write, path):
        """``write`` stopped as its data reaches the disk (Ctrl-C): half written in place
        (``Path.write_text``, ``open``), or before the rename of a whole write; then the
        file read back (the old one, or a cut one that fails)."""
        def go():
            pathlib.Path(path).write_text('{"old": 1}\n')
            real_wt, real_replace = P.Path.write_text, os.replace

            def half(self, data, *a, **k):
                real_wt(self, data[: len(data) // 2], *a, **k)
                raise KeyboardInterrupt

            def cut(*a, **k):
                raise KeyboardInterrupt
            P.Path.write_text, os.replace = half, cut
            try:
                write()
            except KeyboardInterrupt:
                pass
            finally:
                P.Path.write_text, os.replace = real_wt, real_replace
            return json.loads(pathlib.Path(path).read_text())
        return go
    from benchmarks import common
    d = P.Path(fresh("bench"))
    probe("benchmarks write_json over a result, Ctrl-C mid-write (then read)", stopped(lambda: common.write_json("speed", {"new": list(range(1000))}, d), d / "speed.json"), good=True)
    probe("json_values.write_whole over a file, Ctrl-C before the rename (control)", stopped(lambda: json_values.write_whole(d / "w.json", '{"new": 2}'), d / "w.json"), good=True)

    def in_place():
        import re
        pat = re.compile(r"\.write_text\(|json\.dump\(|open\([^)]*,\s*[\"']wb?[\"']|np\.savez\(")
        files = sorted(P.Path(ROOT, "benchmarks").glob("*.py")) + sorted(P.Path(ROOT, "tools").glob("*_reference.py")) + [P.Path(ROOT, "tools", "export_reevaluation.py")]
        bad = [f"{f.name}:{k}" for f in files for k, ln in enumerate(f.read_text().splitlines(), 1)
               if pat.search(ln) and "# temporary" not in ln and "# in memory" not in ln]
        if bad:
            return f"{len(bad)} in-place writes: {', '.join(bad)}"
        return "none"
    probe("results writers writing in place (benchmarks, tools/*_reference.py, export_reevaluation)", lambda: (lambda r: r if r == "none" else (_ for _ in ()).throw(RuntimeError(r)))(in_place()), good=True)


if __name__ == "__main__":
    run([zmx_headers, zmx_pickups, glass_files, report_options, results_files])
