"""Provenance in result.json, and `identify` over many records: jobs, a Dask cluster, resuming, the summary table."""

from __future__ import annotations

import csv
import hashlib
import json
import shutil
from datetime import datetime, timedelta, timezone

import pytest

import flowcurve
from flowcurve.cli import main
from flowcurve.cli.progress import bar_text
from flowcurve.identification import provenance as prov


def _result(folder) -> dict:
    return json.loads((folder / "result.json").read_text(encoding="utf-8"))


def _copies(instron_file, folder, n: int) -> list[str]:
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for k in range(n):
        path = folder / f"T{k}.csv"
        shutil.copyfile(instron_file, path)
        paths.append(str(path))
    return paths


def test_result_json_says_where_it_came_from(tmp_path, instron_file, capsys):
    before = datetime.now(timezone.utc).replace(microsecond=0)
    assert main(["identify", str(instron_file), "--out", str(tmp_path), "--no-plots", "--hardening", "three-point", "--d0", "5.003"]) == 0
    block = _result(tmp_path / instron_file.stem)["provenance"]
    assert block["record_sha256"] == hashlib.sha256(instron_file.read_bytes()).hexdigest()  # what sha256sum prints
    assert block["flowcurve_version"] == flowcurve.__version__
    assert block["options"]["hardening"] == "three_point" and block["options"]["metadata"] == {"specimen.d0_mm": "5.003"}
    assert "workers" not in block["options"] and "ccx_version" not in block  # no solver ran
    date = datetime.fromisoformat(block["date_utc"].replace("Z", "+00:00"))
    assert before <= date <= datetime.now(timezone.utc) + timedelta(seconds=1)


def test_the_same_command_again_skips_current_results_and_redoes_changed_ones(tmp_path, instron_file, capsys):
    records = _copies(instron_file, tmp_path / "in", 2)
    out = tmp_path / "out"
    assert main(["identify", *records, "--out", str(out), "--no-plots"]) == 0
    first = {p: (out / f"T{k}" / "result.json").stat().st_mtime_ns for k, p in enumerate(records)}
    capsys.readouterr()
    assert main(["identify", *records, "--out", str(out), "--no-plots"]) == 0
    text = capsys.readouterr().out
    assert text.count("skipped") >= 2 and "0 identified, 2 skipped" in text
    assert all((out / f"T{k}" / "result.json").stat().st_mtime_ns == first[p] for k, p in enumerate(records))
    # a changed record (one byte more), changed options or --force: identified again
    with open(records[0], "a", encoding="utf-8") as f:
        f.write("\n")
    assert main(["identify", *records, "--out", str(out), "--no-plots"]) == 0
    assert "1 identified, 1 skipped" in capsys.readouterr().out
    assert main(["identify", *records, "--out", str(out), "--no-plots", "--law", "swift"]) == 0
    assert "2 identified, 0 skipped" in capsys.readouterr().out
    assert main(["identify", *records, "--out", str(out), "--no-plots", "--law", "swift", "--force"]) == 0
    assert "2 identified, 0 skipped" in capsys.readouterr().out
    # another flowcurve (version or code) is not current
    block = _result(out / "T1")["provenance"]
    assert prov.same_run(block, block["record_sha256"], block["options"])
    assert not prov.same_run({**block, "flowcurve_version": "0.0.9"}, block["record_sha256"], block["options"])
    assert not prov.same_run({**block, "code_sha256": "0" * 64}, block["record_sha256"], block["options"])


def test_jobs_give_the_results_of_one_by_one_and_one_summary_table(tmp_path, instron_file, capsys):
    records = _copies(instron_file, tmp_path / "in", 3)
    bad = tmp_path / "in" / "empty.csv"
    bad.write_text("", encoding="utf-8")
    code = main(["identify", *records, str(bad), "--out", str(tmp_path / "two"), "--no-plots", "--jobs", "2"])
    err = capsys.readouterr().err
    assert code == 2 and f"flowcurve: error: {bad}" in err and "4/4 records" in err  # the progress bar's last line
    assert main(["identify", records[0], "--out", str(tmp_path / "one"), "--no-plots"]) == 0
    one = _result(tmp_path / "one" / "T0")
    for k in range(3):
        two = _result(tmp_path / "two" / f"T{k}")
        assert {q: two[q] for q in ("E_MPa", "Rp02_MPa", "Rm_MPa", "A_pct")} == {q: one[q] for q in ("E_MPa", "Rp02_MPa", "Rm_MPa", "A_pct")}
    with open(tmp_path / "two" / "summary.csv", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert [r["status"] for r in rows] == ["identified"] * 3 + ["failed"]
    assert float(rows[1]["Rm_MPa"]) == pytest.approx(one["Rm_MPa"]) and rows[1]["record_sha256"] == one["provenance"]["record_sha256"]
    assert "empty" in rows[3]["error"] and rows[3]["Rm_MPa"] == ""


def test_bad_jobs_is_one_line(tmp_path, instron_file, capsys):
    assert main(["identify", str(instron_file), "--out", str(tmp_path), "--jobs", "0"]) != 0
    assert "--jobs must be ≥ 1" in capsys.readouterr().err


def test_records_as_tasks_on_a_dask_cluster(tmp_path, instron_file, capsys):
    distributed = pytest.importorskip("dask.distributed")
    records = _copies(instron_file, tmp_path / "in", 2)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster:
        code = main(["identify", *records, "--out", str(tmp_path / "out"), "--no-plots", "--scheduler", cluster.scheduler_address])
    assert code == 0
    sha = hashlib.sha256(instron_file.read_bytes()).hexdigest()
    assert [_result(tmp_path / "out" / f"T{k}")["provenance"]["record_sha256"] for k in range(2)] == [sha, sha]


def test_progress_bar_text():
    assert bar_text(12, 40, 30.0) == f"[{'#' * 9}{'.' * 21}] 12/40 records, 30 s, about 70 s left"  # 30 s / 12 · 28
    assert bar_text(40, 40, 99.6).endswith("40/40 records, 100 s")


def _no_pool(*_args, **_kwargs):
    raise AssertionError("a process pool was prepared though no record needs work")


def test_jobs_start_no_pool_when_every_result_is_current(tmp_path, instron_file, capsys, monkeypatch):
    import concurrent.futures

    records = _copies(instron_file, tmp_path / "in", 3)
    out = tmp_path / "out"
    assert main(["identify", *records, "--out", str(out), "--no-plots"]) == 0
    capsys.readouterr()
    assert main(["identify", *records, "--out", str(out), "--no-plots", "--jobs", "1"]) == 0
    one, summary_one = capsys.readouterr().out, (out / "summary.csv").read_text(encoding="utf-8")
    monkeypatch.setattr(concurrent.futures, "ProcessPoolExecutor", _no_pool)
    monkeypatch.setattr("flowcurve.cli.identification.preload_identification", _no_pool)
    assert main(["identify", *records, "--out", str(out), "--no-plots", "--jobs", "2"]) == 0
    two = capsys.readouterr().out
    assert "0 identified, 3 skipped" in one and two == one
    assert (out / "summary.csv").read_text(encoding="utf-8") == summary_one


def test_jobs_send_only_the_records_that_need_work_to_the_pool(tmp_path, instron_file, capsys, monkeypatch):
    from flowcurve.identification.fe import pool

    records = _copies(instron_file, tmp_path / "in", 3)
    out_one, out_two = tmp_path / "one", tmp_path / "two"
    assert main(["identify", *records, "--out", str(out_one), "--no-plots"]) == 0
    shutil.copytree(out_one, out_two)
    with open(records[1], "a", encoding="utf-8") as f:  # one byte more: no longer current
        f.write("\n")
    capsys.readouterr()
    assert main(["identify", *records, "--out", str(out_one), "--no-plots", "--jobs", "1"]) == 0
    one = capsys.readouterr().out
    sent, run_many = [], pool.run_many

    def spy(fn, items, **kwargs):
        sent.append([task["path"] for task in items])
        return run_many(fn, items, **kwargs)

    monkeypatch.setattr(pool, "run_many", spy)
    assert main(["identify", *records, "--out", str(out_two), "--no-plots", "--jobs", "2"]) == 0
    two = capsys.readouterr().out
    assert sent == [[records[1]]]
    assert "1 identified, 2 skipped" in one and two.replace(str(out_two), str(out_one)) == one
