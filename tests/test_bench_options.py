"""The benches' shared options (bench/options.py): one declaration gives every bench the same flag,
and figures append to a history instead of replacing it."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
_spec = importlib.util.spec_from_file_location("bench_options", ROOT / "bench" / "options.py")
options = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(options)


def test_figures_append_to_the_file_and_nothing_is_written_without_a_path(tmp_path):
    path = tmp_path / "figures.jsonl"
    options.append_json_lines(str(path), [{"tokens_per_s": 1.0}])
    options.append_json_lines(str(path), [{"tokens_per_s": 2.0}, {"tokens_per_s": 3.0}])
    assert [json.loads(line)["tokens_per_s"] for line in path.read_text().splitlines()] == [1.0, 2.0, 3.0]
    options.append_json_lines(None, [{"tokens_per_s": 4.0}])
    options.append_json_lines("", [{"tokens_per_s": 4.0}])
    assert list(tmp_path.iterdir()) == [path]


def test_shared_flags_parse_with_their_defaults_and_refuse_a_bad_value():
    ap = options.bench_parser("usage line\n    kept as written")
    options.add_preset(ap)
    options.add_seq(ap, 2048, flag="--length")
    options.add_batch(ap, 4)
    options.add_image(ap)
    options.add_attention_impl(ap, "xla")
    options.add_json_lines(ap, "--out")
    a = ap.parse_args([])
    assert (a.preset, a.length, a.batch, a.image, a.impl, a.out) == ("qwen3_vl_4b", 2048, 4, 448, "xla", None)
    assert ap.parse_args(["--impl", "cudnn", "--length", "4096"]).length == 4096
    with pytest.raises(SystemExit):
        ap.parse_args(["--impl", "flash"])
    assert "    kept as written" in ap.format_help()


@pytest.mark.parametrize("script", ["train_step.py", "train_command.py"])
def test_a_bench_run_by_its_path_from_elsewhere_finds_the_shared_options(tmp_path, script):
    """These two parse before importing jax, so their --help is quick; the path insert must reach bench/."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    out = subprocess.run([sys.executable, str(ROOT / "bench" / script), "--help"], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    for flag in ("--preset", "--seq", "--batch", "--json"):
        assert flag in out.stdout
