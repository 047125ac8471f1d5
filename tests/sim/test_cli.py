"""gbmsim info | bench | verify (argparse, exit codes, protocol subcommands registered)."""
import json
import subprocess
import sys

import pytest

from sim import Specimen
from sim.cli import build_parser, main


def test_info_and_bad_file(tmp_path, capsys):
    p = tmp_path / "lat.npz"
    Specimen.lattice(4, 4, 1e-3).save(p)
    assert main(["info", str(p), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["particles"] == 16 and out["parallel_bonds"] == 33 and out["dt_s"] > 0
    assert main(["info", str(tmp_path / "missing.npz")]) == 2
    assert "missing.npz" in capsys.readouterr().err


def test_bench_json(capsys):
    assert main(["bench", "--n", "600", "--steps", "20", "--repeat", "1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["particles"] == 600 and out["particle_steps_per_s"] > 0


def test_verify_all_checks_pass(capsys):
    assert main(["verify", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert len(rows) == 6 and all(r["ok"] for r in rows)


def test_protocol_subcommands_are_registered_and_module_runs():
    choices = build_parser()._subparsers._group_actions[0].choices
    assert {"info", "bench", "verify"} <= set(choices)
    out = subprocess.run([sys.executable, "-m", "sim", "--help"], capture_output=True, text=True)
    assert out.returncode == 0 and "verify" in out.stdout


def test_bad_subcommand_exits_2():
    with pytest.raises(SystemExit) as e:
        main(["nope"])
    assert e.value.code == 2
