"""Pool finished EDoF runs of different seeds into one table.

A paper-scale seed takes longer than one GPU lease, so the seeds of a table may come from
separate runs (separate machines, or pieces resumed from separate checkpoints). This
module reads each run's ``table2_per_image.json``, ``table2.json`` and ``summary.json`` and
writes the table over all their seeds, with the same statistics as one run over those
seeds (the paired bootstrap over seeds and crops included)::

    python -m jaxlens.experiments.edof.merge --out runs/edof_3seeds runs/s0 runs/s1 runs/s2

The runs must agree on everything but their seeds: the configuration, the lenses, the test
crops and the base lens. Anything else is refused, naming what differs, before any file is
written.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shlex
import sys
import types

from jaxlens.experiments.edof.report import checks, table2, table2_markdown
from jaxlens.experiments.runfolder import (
    OneLineParser,
    RunFolder,
    UsageError,
    fail,
    refuse_inside_out,
    within,
)

RUN_FILES = ("table2_per_image.json", "table2.json", "summary.json")
NSR_RTOL = 1e-4
"""Relative tolerance for the runs' Wiener NSR (the same patches give the same value, up
to the float rounding of the machine that computed it)."""


def read_run(folder: str) -> dict:
    """The three result files of a finished run, as ``{file stem: data}``."""
    data = {}
    for name in RUN_FILES:
        path = os.path.join(folder, name)
        if not os.path.isfile(path):
            raise UsageError(f"{folder} is not a finished EDoF run: it has no {name}")
        with open(path) as f:
            try:
                data[name.removesuffix(".json")] = json.load(f)
            except json.JSONDecodeError as e:
                raise UsageError(f"{path}:{e.lineno}: not valid JSON ({e.msg})") from None
    for key, stem, fields in (("per-crop values", "table2_per_image", ("crops", "seeds",
                                                                        "values")),
                              ("table", "table2", ("light_on_sensor", "test", "base_lens",
                                                   "wiener_reference_nsr")),
                              ("summary", "summary", ("config", "command",
                                                      "psf_depth_variation", "odd_terms"))):
        missing = [k for k in fields if not isinstance(data[stem], dict) or k not in data[stem]]
        if missing:
            raise UsageError(f"{os.path.join(folder, stem + '.json')} is not an EDoF run's "
                             f"{key}: it has no {', '.join(missing)}")
    _check_values(data, os.path.join(folder, "table2_per_image.json"))
    return data


def _check_values(data: dict, path: str) -> None:
    """Every listed seed has, for every lens, the same depths, kinds and metrics as the
    first, each with one value per crop (values[seed][lens][depth][kind][metric])."""
    per_image, lenses = data["table2_per_image"], list(data["table2"]["light_on_sensor"])
    values, n = per_image["values"], len(per_image["crops"])

    def layout(entry):  # {depth: {kind: [metrics]}} of a well-formed entry, else None
        if not (isinstance(entry, dict) and entry and all(
                isinstance(k, dict) and all(isinstance(m, dict) for m in k.values())
                for k in entry.values())):
            return None
        return {d: {k: sorted(m) for k, m in kinds.items()} for d, kinds in entry.items()}

    first = None
    for s in per_image["seeds"]:
        for lens in lenses:
            seed_values = values.get(str(s)) if isinstance(values, dict) else None
            entry = seed_values.get(lens) if isinstance(seed_values, dict) else None
            shape = layout(entry)
            first = shape if first is None else first
            if shape is None or shape != first:
                raise UsageError(f"{path}: the per-crop values of seed {s}, lens {lens} are "
                                 f"missing or laid out unlike the others")
            for depth, kinds in entry.items():
                for kind, metrics in kinds.items():
                    for metric, xs in metrics.items():
                        if not isinstance(xs, list) or len(xs) != n:
                            raise UsageError(
                                f"{path}: seed {s}, lens {lens}, {depth} m, {kind} {metric}: "
                                f"{len(xs) if isinstance(xs, list) else 'no list of'} values "
                                f"for {n} crops")


def _same(runs: list[dict], folders: list[str], what: str, get) -> None:
    first = get(runs[0])
    for run, folder in zip(runs[1:], folders[1:], strict=True):
        if get(run) != first:
            raise UsageError(f"{folders[0]} and {folder} differ in {what}; only runs that "
                             f"differ in their seeds can be merged")


def merge_runs(runs: list[dict], folders: list[str]) -> tuple[dict, dict, dict]:
    """``(table, per_image, summary)`` over the seeds of all ``runs`` (:func:`read_run`).

    Raises:
        UsageError: if the runs share a seed or differ in anything but their seeds.
    """
    import numpy as np

    if len(runs) < 2:
        raise UsageError("give at least two run folders to merge")
    configs = [r["summary"]["config"] for r in runs]
    for cfg, folder in zip(configs[1:], folders[1:], strict=True):
        diff = sorted(k for k in set(cfg) | set(configs[0]) if cfg.get(k) != configs[0].get(k))
        if diff:
            raise UsageError(f"{folders[0]} and {folder} were run with other options "
                             f"({', '.join(diff)}); only runs that differ in their seeds can "
                             f"be merged")
    _same(runs, folders, "their lenses", lambda r: list(r["table2"]["light_on_sensor"]))
    _same(runs, folders, "their test crops", lambda r: r["table2_per_image"]["crops"])
    _same(runs, folders, "their test images", lambda r: r["table2"]["test"]["source"])
    _same(runs, folders, "their base lens", lambda r: r["table2"]["base_lens"])
    nsr = [r["table2"]["wiener_reference_nsr"] for r in runs]
    for v, folder in zip(nsr[1:], folders[1:], strict=True):
        if not math.isclose(v, nsr[0], rel_tol=NSR_RTOL):
            raise UsageError(f"{folders[0]} and {folder} differ in their Wiener NSR "
                             f"({nsr[0]:.6g} and {v:.6g}): they saw other training images")

    seeds, values, owner = [], {}, {}
    for run, folder in zip(runs, folders, strict=True):
        for s in run["table2_per_image"]["seeds"]:
            if s in owner:
                raise UsageError(f"seed {s} is in both {owner[s]} and {folder}")
            owner[s] = folder
            seeds.append(s)
            values[str(s)] = run["table2_per_image"]["values"][str(s)]
    names = list(runs[0]["table2"]["light_on_sensor"])
    counts = [len(r["table2_per_image"]["seeds"]) for r in runs]

    def pooled(values):  # one mean per run over its seeds -> one value per seed
        return [v for v, n in zip(values, counts, strict=True) for _ in range(n)]

    crops = runs[0]["table2_per_image"]["crops"]
    test_names = list(dict.fromkeys(c["image"] for c in crops))
    light = {n: pooled([r["table2"]["light_on_sensor"][n] for r in runs]) for n in names}
    table = table2(values, names, seeds, crops, test_names, runs[0]["table2"]["test"]["source"],
                   runs[0]["table2"]["base_lens"], light, nsr[0])
    variation = {}
    for n in names:
        per_run = [r["summary"]["psf_depth_variation"][n] for r in runs]
        variation[n] = {"l1": float(np.mean(pooled([p["l1"] for p in per_run]))),
                        "ncc": float(np.mean(pooled([p["ncc"] for p in per_run]))),
                        "per_seed_l1": [v for p in per_run for v in p["per_seed_l1"]]}
    table["psf_depth_variation"] = variation
    first = runs[0]["summary"]
    summary = {
        "runs": [{"folder": f, "command": r["summary"]["command"],
                  "seeds": r["table2_per_image"]["seeds"],
                  "devices": r["summary"].get("devices"),
                  "timings_s": r["summary"].get("timings_s")}
                 for r, f in zip(runs, folders, strict=True)],
        "config": first["config"],
        "psf_depth_variation": variation,
        # Each run records the trained terms of its first seed.
        "odd_terms": {f"{n}_s{r['table2_per_image']['seeds'][0]}": r["summary"]["odd_terms"][n]
                      for r in runs for n in names},
        "wiener_reference_nsr": nsr[0],
        "noise": first.get("noise"),
        "checks": checks(table),
    }
    per_image = {"crops": crops, "seeds": seeds, "values": values}
    return table, per_image, summary


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(prog="python -m jaxlens.experiments.edof.merge",
                      description=__doc__.split("\n\n")[0])
    p.add_argument("runs", nargs="+", help="finished run folders (each with table2.json)")
    p.add_argument("--out", required=True, help="folder for the merged table")
    p.add_argument("--overwrite", action="store_true", help="replace an earlier merge in --out")
    return p


def run(argv=None) -> dict:
    """Merge the runs named in ``argv``; returns the merged summary."""
    argv = list(sys.argv[1:] if argv is None else argv)
    a = build_parser().parse_args(argv)
    for r in a.runs:
        # With --overwrite, --out naming an input run replaced that run by the merge.
        if within(a.out, r):
            raise UsageError(f"--out {a.out} is the run folder {r} (or inside it), one of the "
                             f"runs to merge; choose another folder for the merged table")
    # A run inside --out went when --overwrite replaced --out by the merge.
    refuse_inside_out(a.out, (("run", r) for r in a.runs), "edof.merge")
    folder = RunFolder(a.out, overwrite=a.overwrite)
    runs = [read_run(r) for r in a.runs]
    table, per_image, summary = merge_runs(runs, a.runs)
    command = "python -m jaxlens.experiments.edof.merge " + shlex.join(argv)
    summary = {"command": command, **summary}
    # The runs' recorded options, read by name (a run written by another version may
    # have fields that this version's Config lacks).
    cfg = types.SimpleNamespace(**summary["config"])
    md = table2_markdown(table, command, cfg) + "\nMerged runs:\n\n" + "".join(
        f"- seeds {r['seeds']}: `{r['command']}`\n" for r in summary["runs"])
    out = folder.start()
    try:
        for name, data in (("table2.json", table), ("table2_per_image.json", per_image),
                           ("summary.json", summary)):
            with open(os.path.join(out, name), "w") as f:
                json.dump(data, f, indent=None if name == "table2_per_image.json" else 2)
        with open(os.path.join(out, "table2.md"), "w") as f:
            f.write(md)
        with open(os.path.join(out, "command.txt"), "w") as f:
            f.write(command + "\n")
        final = folder.finish()
    except BaseException:
        folder.abandon()
        raise
    print(md)
    print(f"outputs in {final}")
    return summary


def main() -> None:
    try:
        run()
    except UsageError as e:
        sys.exit(fail("python -m jaxlens.experiments.edof.merge", e))


if __name__ == "__main__":
    main()
