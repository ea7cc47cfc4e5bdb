#!/usr/bin/env python3
"""The papers' tables from the sweeps of docs/studies/*.json, as Markdown.

Usage: study_tables.py OUT_DIR   (the folder scripts/studies writes: OUT_DIR/NAME/results.csv)

Prints the dissertation's Tables 4.1-4.13, the secant paper's Fig. 4 numbers, the ACM
paper's Fig. 3 numbers and the exact reference's missed geometry per method, in the
layout docs/studies.md shows. A study whose folder is absent (its map is not here) is
skipped with a note. Columns: avg steps = avg_iterations; avg refine =
avg_refine_iterations; MSE = mse_paper (the dissertation's metric); exact =
mse_exact_depth (against the exact first hit); uv err = uv_error_texels_mean; past % =
past_first_hit_share in percent; missed = missed_geometry_pixels; fetches, max =
avg_fetches, max_fetches; cost = lane_cost_warp32 / covered_pixels (the trips a 32-lane
warp executes per pixel: the simulator's deterministic stand-in for frame time).
"""
import csv
import os
import sys

METRICS = {
    "avg steps": lambda r: "%.3f" % float(r["avg_iterations"]),
    "avg refine": lambda r: "%.3f" % float(r["avg_refine_iterations"]),
    "MSE": lambda r: "%.3g" % float(r["mse_paper"]),
    "exact": lambda r: "%.3g" % float(r["mse_exact_depth"]),
    "uv err": lambda r: "%.3f" % float(r["uv_error_texels_mean"]),
    "past %": lambda r: "%.2f" % (100 * float(r["past_first_hit_share"])),
    "missed": lambda r: r["missed_geometry_pixels"],
    "fetches": lambda r: "%.2f" % float(r["avg_fetches"]),
    "max": lambda r: r["max_fetches"],
    "cost": lambda r: "%.2f" % (float(r["lane_cost_warp32"]) / float(r["covered_pixels"])),
}


def load(out, study):
    path = os.path.join(out, study, "results.csv")
    if not os.path.exists(path):
        return None
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def matches(row, where):
    return all(row.get(k, "") == str(v) for k, v in where.items())


def table(rows, title, keys, blocks, cols, where=None):
    """One row per value of `keys` (set.* columns), one column group per block."""
    rows = [r for r in rows if matches(r, where or {})]
    order = []
    for r in rows:
        k = tuple(r["set." + c] for c in keys)
        if any(matches(r, b) for _, b in blocks) and k not in order:
            order.append(k)
    def numeric(k):
        return tuple((0, float(x), "") if x.replace(".", "", 1).isdigit() else (1, 0.0, x)
                     for x in k)
    order.sort(key=numeric)
    head = list(keys) + ["%s %s" % (label, c) for label, _ in blocks for c in cols]
    lines = ["**%s**" % title, "", "| " + " | ".join(head) + " |",
             "|" + "---|" * len(head)]
    for k in order:
        cells = list(k)
        for _, b in blocks:
            hit = [r for r in rows if matches(r, b)
                   and tuple(r["set." + c] for c in keys) == k]
            cells += [METRICS[c](hit[0]) if hit else "" for c in cols]
        lines.append("| " + " | ".join(cells) + " |")
    print("\n".join(lines) + "\n")


def dissertation(rows, name):
    print("### Dissertation tables on %s\n" % name)
    c3 = ["avg steps", "MSE", "exact", "cost"]
    table(rows, "Table 4.1: linear search", ["linear_steps"],
          [("linear", {"method": "linear"})], c3 + ["missed"])
    table(rows, "Tables 4.2 and 4.4: binary and interval refinement",
          ["linear_steps", "refine_steps"],
          [("binary", {"method": "relief"}), ("interval", {"method": "interval"})],
          ["MSE", "exact", "cost"], where={})
    table(rows, "Table 4.3: linear + 2 binary steps (compare with Table 4.1)",
          ["linear_steps"], [("relief", {"method": "relief", "set.refine_steps": 2})],
          c3)
    table(rows, "Tables 4.6 and 4.7: CSM alone and with 2 binary steps", ["cone_steps"],
          [("csm", {"method": "csm", "set.refine": "none"}),
           ("csm+2 binary", {"method": "csm", "set.refine": "binary",
                             "set.refine_steps": 2})], c3)
    table(rows, "Table 4.8: CSM vs QCSM (no refinement)", ["cone_steps"],
          [("csm", {"method": "csm", "set.refine": "none"}),
           ("qcsm", {"method": "qcsm", "set.refine": "none"})], c3)
    five = {"set.refine": "binary", "set.refine_steps": 5}
    for title, pair in (
            ("Table 4.9: CSM vs QCSM vs RCS, 5 binary steps", ("csm", "qcsm", "rcs")),
            ("Table 4.11: CSM vs CNS, 5 binary steps", ("csm", "cns")),
            ("Table 4.12: RCS vs RCNS, 5 binary steps", ("rcs", "rcns")),
            ("Table 4.13: CNS vs MCNS, 5 binary steps", ("cns", "mcns"))):
        table(rows, title, ["cone_steps"],
              [(m, dict(method=m, **five)) for m in pair], c3)
    table(rows, "Table 4.10: RCS, binary vs interval refinement",
          ["cone_steps", "refine_steps"],
          [("binary", {"method": "rcs", "set.refine": "binary"}),
           ("interval", {"method": "rcs", "set.refine": "interval"})],
          ["MSE", "exact", "cost"])


def per_view(rows, title, keys, blocks, cols):
    maps = list(dict.fromkeys(r["map"] for r in rows))
    views = list(dict.fromkeys(r["view"] for r in rows))
    for m in maps:
        for v in views:
            table(rows, "%s: %s, view %s" % (title, m, v), keys, blocks, cols,
                  where={"map": m, "view": v})


def main(out):
    print("# The papers' studies, re-measured\n\nWritten by `scripts/studies` "
          "(docs/studies.md explains it); every number is deterministic.\n"
          "Columns: " + __doc__.split("Columns: ")[1].strip().replace("\n", " ") + "\n")
    for study, name in (("dissertation", "builtin:shapes"),
                        ("dissertation-rocks", "DX SDK rocks (A)")):
        rows = load(out, study)
        if rows is None:
            print("(%s: not run)\n" % study)
        else:
            dissertation(rows, name)
    rows = load(out, "secant-fig4")
    if rows:
        print("### Secant paper, Fig. 4 (ortho views, 5 linear steps)\n")
        per_view(rows, "secant vs binary", ["refine_steps", "secant_tolerance"],
                 [("secant", {"method": "secant"}), ("binary", {"method": "relief"})],
                 ["avg refine", "MSE", "exact", "uv err"])
    rows = load(out, "acm-fig3")
    if rows:
        print("### ACM paper, Fig. 3 (no refinement)\n")
        for f in ("bilinear", "min4"):
            per_view(rows, "CSM vs ACM4 vs ACM8, cone_filter=" + f, ["cone_steps"],
                     [(m, {"method": m, "set.cone_filter": f})
                      for m in ("csm", "acm4", "acm8")],
                     ["avg steps", "exact", "uv err", "cost"])
    rows = load(out, "missed-geometry")
    if rows:
        print("### What the exact reference adds: every method at its defaults\n")
        maps = list(dict.fromkeys(r["map"] for r in rows))
        views = list(dict.fromkeys(r["view"] for r in rows))
        for m in maps:
            for v in views:
                sel = [r for r in rows if r["map"] == m and r["view"] == v]
                cols = ["fetches", "max", "MSE", "exact", "past %", "missed", "cost"]
                print("**%s, view %s**\n" % (m, v))
                print("| method | " + " | ".join(cols) + " |")
                print("|" + "---|" * (len(cols) + 1))
                for r in sel:
                    print("| %s | %s |" % (r["method"],
                                           " | ".join(METRICS[c](r) for c in cols)))
                print()
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print("usage: study_tables.py OUT_DIR", file=sys.stderr)
        sys.exit(1)
    sys.exit(main(sys.argv[1]))
