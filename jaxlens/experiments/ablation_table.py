"""Table 1 of the classical ablation (``python -m jaxlens.experiments.classical --ablation``):
its column files and the table built from them.

Columns may come from separate processes (``--columns`` subsets run side by side) into one
``--ablation-out`` folder, so a run checks the columns already there before it designs its
own: one cut short (a run interrupted while writing it) or one designed for another spec
(``--fov 60`` beside the default 80.8°) would have been read into, or put beside, this
run's table. A column is written whole or not at all (a temporary file renamed).
"""

from __future__ import annotations

import dataclasses
import json
import os


def fmt(x, nd=2) -> str:
    """A table number: ``nd`` decimals, a dash for a missing one (an internal helper of the
    table: a str, a bool or a complex is refused by ``real_number``'s TypeError)."""
    from jaxlens.analysis.report_cells import real_number

    if isinstance(nd, bool) or not isinstance(nd, int) or nd < 0:
        raise TypeError(f"fmt: nd must be a whole number >= 0 (decimals), got {nd!r}")
    return "–" if x is None else f"{real_number(x, 'x', 'fmt'):.{nd}f}"


def column_file(out: str, name: str) -> str:
    """The JSON file of ablation column ``name`` in the ablation folder ``out``."""
    stem = name.replace("+", "plus_").strip("_") or "baseline"
    return os.path.join(out, "columns", f"{stem}.json")


def spec_data(spec) -> dict:
    """A ``DesignSpec`` as the JSON data the column files and ``table1.json`` hold."""
    return json.loads(json.dumps(dataclasses.asdict(spec), default=float))


def write_column(out: str, name: str, col: dict) -> str:
    """Write column ``name``: into a temporary file first, renamed when complete, so an
    interrupted run leaves no half-written column for the next run's table."""
    path = column_file(out, name)
    tmp = path + ".partial"
    with open(tmp, "w") as f:
        json.dump(col, f, indent=2, default=float)
    os.replace(tmp, path)
    return path


def read_column(path: str) -> dict:
    """One column file, or a ValueError naming it (not JSON, or not a column)."""
    from jaxlens.optics.input_files import input_file

    try:
        input_file(path, "ablation table", "column file")  # a FIFO column.json hung here
        with open(path) as f:
            col = json.load(f)
    except (OSError, ValueError) as e:
        raise ValueError(f"{path} is not a readable ablation column ({e}; cut short by an "
                         f"interrupted run?); remove it, or give --overwrite and its column "
                         f"in --columns to design it again") from None
    if not isinstance(col, dict) or "switches" not in col or "command" not in col:
        raise ValueError(f"{path} is not an ablation column (no 'switches' and 'command'); "
                         f"remove it, or choose another --ablation-out")
    return col


def column_paths(out: str) -> list[str]:
    """The column files of the ablation folder ``out``, sorted by name."""
    folder = os.path.join(out, "columns")
    names = sorted(os.listdir(folder)) if os.path.isdir(folder) else []
    return [os.path.join(folder, n) for n in names if n.endswith(".json")]


def check_columns(out: str, spec, replaced: list[str]) -> None:
    """Refuse the columns in ``out`` that this run's table cannot hold: unreadable ones and
    ones of another spec (the spec a column records, else ``table1.json``'s). ``replaced``:
    the column files this run writes over (``--overwrite``), not checked."""
    mine = spec_data(spec)
    table = os.path.join(out, "table1.json")
    table_spec = None
    if os.path.isfile(table):
        try:
            with open(table) as f:
                table_spec = json.load(f).get("spec")
        except (OSError, ValueError, AttributeError):
            table_spec = None  # rebuilt from the columns at the end
    for path in column_paths(out):
        if os.path.abspath(path) in replaced:
            continue
        col = read_column(path)
        theirs = col.get("spec", table_spec)
        if theirs is None or theirs == mine:
            continue
        diff = sorted(k for k in set(theirs) | set(mine) if theirs.get(k) != mine.get(k))
        raise ValueError(f"{path} is a column of another spec ("
                         + ", ".join(f"{k} {theirs.get(k)!r}, this run {mine.get(k)!r}"
                                     for k in diff[:4])
                         + "); one table holds columns of one spec: choose another "
                           "--ablation-out, or run with the same spec options")


def build_table(out: str, spec, columns, convention: str, paper: dict) -> dict:
    """Collect ``columns/*.json`` into ``table1.json``, ``table1.md`` and ``command.txt``.

    ``columns``: the ``(name, switches)`` pairs of the table, in its order; ``paper``: the
    paper's full-method figures.
    """
    cols = {}
    for path in column_paths(out):
        col = read_column(path)
        name = next((n for n, sw in columns if sw == col["switches"]),
                    os.path.basename(path)[:-5])
        cols[name] = col
    commands = sorted({c["command"] for c in cols.values()})
    table = {"commands": commands, "convention": convention, "spec": spec_data(spec),
             "paper_full_method": paper,
             "columns": {n: cols[n] for n, _ in columns if n in cols}}
    with open(os.path.join(out, "table1.json"), "w") as f:
        json.dump(table, f, indent=2, default=float)
    write_table_md(table, os.path.join(out, "table1.md"), [n for n, _ in columns])
    with open(os.path.join(out, "command.txt"), "w") as f:
        f.write("\n".join(commands) + "\n")
    return table


def write_table_md(table: dict, path: str, order: list[str]) -> None:
    """``table1.md``: the columns of ``table`` in the order ``order``."""
    cols = [c for c in order if c in table["columns"]]
    lines = ["# Table 1 (jaxlens): ablation of the curriculum design", "",
             "Commands: " + "; ".join(f"`{c}`" for c in table["commands"]), "",
             f"Convention: {table['convention']}.", "",
             "| | " + " | ".join(cols) + " | paper (+both+mask) |",
             "|---|" + "---|" * (len(cols) + 1)]
    c = table["columns"]
    p = table["paper_full_method"]
    lines.append("| random starts (seeds) | " + " | ".join(
        f"{len(c[k]['seeds'])} ({min(c[k]['seeds'])}–{max(c[k]['seeds'])})" for k in cols) +
        " | 20 |")
    rows = [
        ("designs without self-intersection (%)", "no_self_intersection_percent", 0,
         fmt(p["valid_percent"], 0)),
        ("valid designs (%) (no self-intersection, ≥ 99 % rays reach the sensor)",
         "valid_percent", 0, "–"),
        ("average RMS spot of valid designs, 256 fields (µm)", "rms_mean_um", 2,
         fmt(p["rms_mean_um"])),
        ("minimum RMS spot of valid designs, 256 fields (µm)", "rms_min_um", 2,
         fmt(p["rms_min_um"])),
        ("worst RMS spot of valid designs, 256 fields (µm)", "rms_max_um", 2, "–"),
        ("wall time per design (s)", "seconds_per_design", 1, "–"),
    ]
    for label, key, nd, paper in rows:
        lines.append(f"| {label} | " + " | ".join(fmt(c[k].get(key), nd) for k in cols) +
                     f" | {paper} |")
    devices = sorted({c[k].get("devices", 1) for k in cols})
    loads = [c[k]["load_average"] for k in cols if c[k].get("load_average") is not None]
    load = (f" The 1-minute load average at the end of each column: "
            f"{', '.join(f'{x:.1f}' for x in loads)} (other jobs shared the cores)."
            if loads else "")
    lines += ["", f"{'/'.join(map(str, devices))} XLA CPU device(s). Wall time per design = the "
              f"column's wall time (all its seeds designed together) / seeds.{load}", ""]
    with open(path, "w") as f:
        f.write("\n".join(lines))


if __name__ == "__main__":  # before: it ran as a module, did nothing and exited 0
    import sys

    print("python -m jaxlens.experiments.ablation_table: error: this module holds the Table 1 "
          "helpers and is no command; the table is built by python -m "
          "jaxlens.experiments.classical --ablation (--ablation-out DIR, --columns ...)",
          file=sys.stderr)
    sys.exit(2)
