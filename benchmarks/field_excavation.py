"""Field-scale benchmark (thesis Ch. 7): the single drive with the thesis-ch7 ring plan excavated
at 200, 400 and 600 m (sleeping on) and at 400 m with sleeping off; wall time beside the
damage it reached (max D/R, notch depth, height and angle) and the thesis's table.

    python benchmarks/field_excavation.py [--jobs 2] [--out benchmarks/field_results]

One command builds the specimen (``gbmgen field --opening drive --seed 1``), runs each case
as ``gbmsim excavate`` in its own process (NUMBA_NUM_THREADS=1 each, ``--jobs`` at a time;
cases already finished in ``--out`` are kept: delete a case's directory to run it again) and
writes ``field_excavation.json`` and ``field_excavation.md``. Records the machine load
(``os.getloadavg``) at the start and end of every case: wall times on a shared machine are
provisional.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

#: Thesis single-drive table (REFERENCE.md "Field scale"): depth -> notch height m, angle deg.
THESIS = {200: (1.14, 120.0), 400: (1.43, 130.0), 600: (2.05, 135.0)}
THESIS_MAX_DR = 1.3
CASES = (("d200", 200, True), ("d400", 400, True), ("d600", 600, True),
         ("d400_nosleep", 400, False))


def _run_case(out, spec, name, depth, sleep, extra):
    d = os.path.join(out, name)
    if os.path.exists(os.path.join(d, "summary.json")) and \
            json.load(open(os.path.join(d, "run_state.json")))["phase"] == "done":
        return name
    cmd = [sys.executable, "-m", "sim", "excavate", spec, "--depth-m", str(depth), "--out", d,
           "--no-progress"] + ([] if sleep else ["--no-sleep"]) + list(extra)
    if os.path.exists(os.path.join(d, "checkpoint.npz")):
        cmd.append("--resume")
    env = dict(os.environ, NUMBA_NUM_THREADS=os.environ.get("NUMBA_NUM_THREADS", "1"))
    os.makedirs(d, exist_ok=True)
    load0 = os.getloadavg()
    t0 = time.time()
    with open(os.path.join(d, "run.log"), "a") as log:
        rc = subprocess.call(cmd, env=env, stdout=log, stderr=subprocess.STDOUT)
    json.dump({"rc": rc, "wall_s_process": time.time() - t0, "load_start": load0,
               "load_end": os.getloadavg(), "command": " ".join(cmd),
               "threads": env["NUMBA_NUM_THREADS"]},
              open(os.path.join(d, "bench.json"), "w"), indent=1)
    return name


def _row(out, name, depth, sleep):
    d = os.path.join(out, name)
    s = json.load(open(os.path.join(d, "summary.json")))
    b = json.load(open(os.path.join(d, "bench.json"))) if os.path.exists(
        os.path.join(d, "bench.json")) else {}
    o = s["openings"][0]
    nt = o["notches"][0] if o["notches"] else {}
    ph = s["phases"]
    n = s["particles"]
    steps = {k: v["steps"] for k, v in ph.items()}
    wall = {k: v["wall_s"] for k, v in ph.items()}
    return {"case": name, "depth_m": depth, "sleep": sleep, "particles_after": n,
            "steps": steps, "wall_s": wall, "wall_s_total": sum(wall.values()),
            "converged": {k: v["converged"] for k, v in ph.items()},
            "load_start": b.get("load_start"), "load_end": b.get("load_end"),
            "threads": b.get("threads"),
            "max_D_over_R": o["max_D_over_R"], "max_D_over_R_angle_deg":
                o["max_D_over_R_angle_deg"], "max_depth_m": o["max_depth_m"],
            "notch_depth_m": nt.get("depth_m"), "notch_height_m": nt.get("height_m"),
            "notch_angle_deg": nt.get("angle_deg"), "notch_tip_deg": nt.get("tip_angle_deg"),
            "cracks_excavation": s["cracks"]["total"], "cracks_insitu": s["cracks_insitu"],
            "thesis_notch_height_m": THESIS.get(depth, (None, None))[0],
            "thesis_notch_angle_deg": THESIS.get(depth, (None, None))[1]}


def _table(rows):
    f = lambda v, p=2: "–" if v is None else f"{v:.{p}f}"  # noqa: E731
    lines = ["| case | depth m | sleep | in-situ steps / s | excavation steps / s | total s | "
             "load | max D/R (deg) | notch depth m | notch height m (thesis) | "
             "notch angle deg (thesis) | cracks |", "|" + "---|" * 12]
    for r in rows:
        st, wl = r["steps"], r["wall_s"]
        ex = [k for k in st if k.startswith("excavate")]
        lines.append(
            f"| {r['case']} | {r['depth_m']} | {'on' if r['sleep'] else 'off'} | "
            f"{st.get('insitu')} / {f(wl.get('insitu'), 0)} | "
            f"{sum(st[k] for k in ex)} / {f(sum(wl[k] for k in ex), 0)} | "
            f"{f(r['wall_s_total'], 0)} | {f(r['load_start'][0] if r['load_start'] else None, 1)}"
            f"–{f(r['load_end'][0] if r['load_end'] else None, 1)} | "
            f"{f(r['max_D_over_R'], 3)} ({f(r['max_D_over_R_angle_deg'], 1)}) | "
            f"{f(r['notch_depth_m'])} | {f(r['notch_height_m'])} "
            f"({f(r['thesis_notch_height_m'])}) | {f(r['notch_angle_deg'], 0)} "
            f"({f(r['thesis_notch_angle_deg'], 0)}) | {r['cracks_excavation']} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="benchmarks/field_results")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--cases", default=",".join(c[0] for c in CASES))
    p.add_argument("--extra", default="", help="extra gbmsim excavate flags (quoted)")
    a = p.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    spec = os.path.join(a.out, f"drive40_seed{a.seed}.npz")
    if not os.path.exists(spec):
        subprocess.check_call([sys.executable, "-m", "gbmgen", "field", "--opening", "drive",
                               "--seed", str(a.seed), "--out", spec, "--json",
                               "--no-progress"], stdout=open(spec + ".json", "w"))
    want = a.cases.split(",")
    cases = [c for c in CASES if c[0] in want]
    with ThreadPoolExecutor(max_workers=a.jobs) as ex:
        list(ex.map(lambda c: _run_case(a.out, spec, *c, a.extra.split()), cases))
    rows = [_row(a.out, *c) for c in cases
            if os.path.exists(os.path.join(a.out, c[0], "summary.json"))]
    json.dump({"specimen": spec, "thesis_max_D_over_R": THESIS_MAX_DR, "rows": rows},
              open(os.path.join(a.out, "field_excavation.json"), "w"), indent=1)
    with open(os.path.join(a.out, "field_excavation.md"), "w") as fh:
        fh.write(_table(rows))
    print(_table(rows))


if __name__ == "__main__":
    main()
