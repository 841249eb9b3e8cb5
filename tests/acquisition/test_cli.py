"""flowcurve run / annotate / recover from the command line: results and one-line errors."""

import numpy as np
import pytest

from flowcurve.record.format import RecordWriter, read_record
from flowcurve.cli import main


def small_record(path, status_complete=True, partial_tail=False):
    w = RecordWriter(path, {"test": "compression", "specimen.d0_mm": 10.0, "specimen.h0_mm": 15.0}, ["time_s", "force_N", "crosshead_mm"])
    w.append_rows(np.column_stack([np.arange(20) * 0.1, np.arange(20) * 100.0, np.arange(20) * 0.01]))
    w.event(1.0, "start")
    if status_complete:
        w.close()
    else:  # a process killed mid-test: status 'recording', maybe a partial line
        w._fh.flush()
        if partial_tail:
            w._fh.write("2.000000,20")
            w._fh.flush()
        w._fh.close()
    return path


def run_cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_annotate_sets_and_removes_keys(tmp_path, capsys):
    p = small_record(tmp_path / "r.csv")
    code, out, _ = run_cli(capsys, "annotate", p, "--set", "post.hk_mm=7.5", "--set", "operator=Petrov")
    assert code == 0 and "post.hk_mm = 7.5" in out and "still missing: post.dmax_mm" in out
    rec = read_record(p)
    assert rec.meta["post.hk_mm"] == "7.5" and rec.meta["operator"] == "Petrov"
    assert len(rec.data) == 20 and rec.events[0].name == "start"  # samples and events untouched
    code, out, _ = run_cli(capsys, "annotate", p, "--set", "operator=")
    assert "operator" not in read_record(p).meta


@pytest.mark.parametrize("setting,message", [
    ("post.hk_mm=abc", "must be a number"),
    ("post.hk_mm=-1", "must be > 0"),
    ("nokey", "KEY=VALUE"),
    ("status=complete", "managed by flowcurve"),
])
def test_annotate_bad_input_is_one_line(tmp_path, capsys, setting, message):
    p = small_record(tmp_path / "r.csv")
    before = p.read_text()
    code, _, err = run_cli(capsys, "annotate", p, "--set", setting)
    assert code == 2 and message in err and err.count("\n") == 1 and "Traceback" not in err
    assert p.read_text() == before


@pytest.mark.parametrize("setting,near", [("hk=3", "post.hk_mm"), ("post.hk=3", "post.hk_mm"), ("dmax=7.1", "post.dmax_mm"),
                                          ("specimen.d0=6", "specimen.d0_mm"), ("Operator=Ivanov", "operator")])
def test_annotate_refuses_an_unknown_key_naming_the_nearest(tmp_path, capsys, setting, near):
    """Issue 42: 'annotate --set hk=3' wrote '# hk: 3', which nothing reads; now refused, nothing
    written, with the nearest known key (failed on the old code: exit 0 and the key written)."""
    p = small_record(tmp_path / "r.csv")
    before = p.read_text()
    code, _, err = run_cli(capsys, "annotate", p, "--set", "post.dmax_mm=7", "--set", setting)
    assert code == 2 and f"did you mean {near}?" in err and err.count("\n") == 1
    assert p.read_text() == before  # the good key before it is not written either


def test_run_post_refuses_an_unknown_key_before_the_test(tmp_path, capsys):
    """Issue 42: 'run --post hk=3' dropped the value silently; now refused before anything runs
    (failed on the old code: the test ran and the record had no post.hk_mm)."""
    out = tmp_path / "c.csv"
    code, _, err = run_cli(capsys, "run", "compression", "--quiet", "--out", out, "--target", "0.5", "--post", "hk=3")
    assert code == 2 and "--post hk=3" in err and "did you mean post.hk_mm?" in err and not out.exists()
    code, _, err = run_cli(capsys, "run", "tension", "--quiet", "--out", out, "--target", "0.5", "--post", "post.hk_mm=3")
    assert code == 2 and "'post.hk_mm' is not one of the keys taken here" in err and "post.lu_mm" in err and not out.exists()  # not a tension measurement


def test_annotate_not_a_record(tmp_path, capsys):
    p = tmp_path / "x.csv"
    p.write_text("a,b\n1,2\n")
    code, _, err = run_cli(capsys, "annotate", p, "--set", "post.hk_mm=1")
    assert code == 2 and "x.csv" in err and "not a flowcurve-record" in err and err.count("\n") == 1


def test_recover_completes_a_cut_record(tmp_path, capsys):
    p = small_record(tmp_path / "r.csv", status_complete=False, partial_tail=True)
    assert read_record(p).truncated
    code, out, _ = run_cli(capsys, "recover", p)
    assert code == 0 and "20 samples up to 1.9 s" in out
    rec = read_record(p)
    assert rec.meta["status"] == "aborted" and not rec.truncated and len(rec.data) == 20
    code, out, _ = run_cli(capsys, "recover", p)  # twice: nothing to do
    assert code == 0 and "nothing to recover" in out


def assert_complete_run(code, err, path):
    """Exit 0 — or, on ptys in real time, 5 when a loaded PC starved the virtual amplifier's thread
    and it skipped frames, which the record then declares (never a corrupt reading)."""
    assert code in (0, 5), err
    rec = read_record(path)
    if code == 5 and "data_loss" in rec.meta:
        assert "force samples lost" in rec.meta["data_loss"] and "corrupt" not in rec.meta["data_loss"], err


@pytest.fixture
def virtual_runs_on(monkeypatch, device_link):
    """``flowcurve run`` without a configuration runs the virtual rig on ``device_link``: in
    this process on model time, or (as the command does) on ptys in real time (``-m pty``)."""
    from flowcurve.acquisition import session

    if device_link["link"] != "pty":
        real = session.run_virtual_test
        monkeypatch.setattr(session, "run_virtual_test", lambda *args, **kwargs: real(*args, **device_link, **kwargs))
    return device_link


@pytest.mark.parametrize("mode", [[], ["--poll"]])
def test_run_virtual_compression_from_the_command_line(tmp_path, capsys, mode, virtual_runs_on):
    p = tmp_path / "c.csv"
    code, out, err = run_cli(capsys, "run", "compression", "--quiet", "--time-scale", "60", "--out", p, "--operator", "Ivanova", "--specimen-id", "C-7", *mode)
    assert_complete_run(code, err, p)
    assert f"record: {p}" in out and "complete" in out and "post.hk_mm=" in out
    rec = read_record(p)
    assert rec.meta["operator"] == "Ivanova" and rec.meta["specimen.id"] == "C-7"
    assert rec.meta["material"] == "steel45" and float(rec.meta["post.hk_mm"]) < float(rec.meta["specimen.h0_mm"])
    assert rec.column("force_N").max() > 20e3
    rate = len(rec.data) / (rec.column("time_s")[-1] / 60.0)  # samples per host second
    if virtual_runs_on["link"] == "pty":  # an instant pty, a loaded machine: about 100 values/s
        assert 50 < rate < 130
    elif mode:  # polled: each ';MSV?;' and its 10-byte answer take 16 bytes x 10 bits at 9600 baud
        assert 40 < rate <= 9600 / (10 * 16)
    else:  # streamed: the amplifier's 100 values/s
        assert 90 < rate <= 100


@pytest.mark.parametrize("args,message", [
    (["run", "tension", "--config", "/nonexistent/rig.toml", "--quiet", "--d0", "6", "--l0", "30"], "rig.toml"),
    (["run", "tension", "--quiet", "--d0", "-6"], "--d0 must be more than 0 and at most 30 mm"),
    (["run", "tension", "--quiet", "--time-scale", "0"], "--time-scale must be a positive number"),
    (["run", "tension", "--quiet", "--temperature", "5000"], "below 900 C (the furnace's [furnace] max_temperature_C), got 5000"),
    (["run", "tension", "--quiet", "--post", "post.lu_mm=x"], "must be a number"),
    (["run", "tension", "--quiet", "--lc", "25"], "--lc 25 mm is shorter than the gauge length l0 30 mm"),  # the virtual bar's l0
    (["run", "tension", "--quiet", "--l0", "40", "--lc", "35"], "--lc 35 mm is shorter than the gauge length l0 40 mm"),
    (["run", "tension", "--quiet", "--lc", "1e4"], "--lc must be more than 0 and at most 200 mm"),
])
def test_run_bad_input_is_one_line(tmp_path, capsys, args, message):
    code, out, err = run_cli(capsys, *args, "--out", tmp_path / "r.csv")
    assert code == 2 and message in err and err.count("\n") == 1 and "Traceback" not in err, err


def test_run_with_config_needs_geometry(tmp_path, capsys):
    from flowcurve.rig.config import to_toml
    from flowcurve.rig.virtual.rig import VirtualRig

    with VirtualRig("steel45") as vr:
        cfg = tmp_path / "rig.toml"
        cfg.write_text(to_toml(vr.config()))
        code, _, err = run_cli(capsys, "run", "tension", "--config", cfg, "--quiet", "--d0", "6", "--out", tmp_path / "r.csv")
    assert code == 2 and "give --l0" in err


def le_roy_smooth_a_over_R(rec):
    """a/R the analytic mirror gives at the record's dk and du: 1.1·δ²/(δ + ε_u), δ = ε_f − ε_u."""
    d0 = float(rec.meta["specimen.d0_mm"])
    eps_f = 2 * np.log(d0 / float(rec.meta["post.dk_mm"]))
    eps_u = 2 * np.log(d0 / float(rec.meta["post.du_mm"]))
    d = eps_f - eps_u
    return 1.1 * d * d / (d + eps_u)


@pytest.mark.parametrize("response", ["bridgman", "fe"])
def test_run_tension_response_option_reaches_the_rig_and_the_header(tmp_path, capsys, virtual_runs_on, response):
    p = tmp_path / "t.csv"
    code, out, err = run_cli(capsys, "run", "tension", "--quiet", "--time-scale", "60", "--out", p, "--tension-response", response)
    assert_complete_run(code, err, p)
    rec = read_record(p)
    assert rec.meta["virtual.tension_response"] == response and f"tension response {response}" in rec.meta["rig.virtual"]
    a_over_R = float(rec.meta["post.dk_mm"]) / 2 / float(rec.meta["post.neck_radius_mm"])
    if response == "bridgman":  # the neck radius is Le Roy's
        assert a_over_R == pytest.approx(le_roy_smooth_a_over_R(rec), rel=3e-3)
    else:  # the CalculiX neck is blunter (tests/rig/virtual/test_neck_response.py)
        assert a_over_R < 0.85 * le_roy_smooth_a_over_R(rec)


def elongation_at(rec, fractions) -> np.ndarray:
    """The specimen's elongation, mm (crosshead less the frame's F/C, C the header's stiffness), where
    the rising force first reaches ``fractions`` of its maximum (the running maximum, so noise cannot go back)."""
    force, cross = rec.column("force_N"), rec.column("crosshead_mm")
    top = int(np.argmax(force))
    rising = np.maximum.accumulate(force[: top + 1])
    at = np.asarray(fractions) * force[top]
    x = np.array([np.interp(level, rising, cross[: top + 1]) for level in at])  # first crossing: rising is non-decreasing
    return x - at / (float(rec.meta["rig.frame_stiffness_N_per_um"]) * 1e3)


def test_run_lc_reaches_the_header_and_the_virtual_bar_stretches_it(tmp_path, capsys, virtual_runs_on):
    """--lc 42 --l0 30: the header states it and the virtual bar is 42 mm long between its shoulders.
    Against a bar of Lc = l0 at the same strain rate v/Lc (0.07/42 = 0.05/30): the same force on the
    rising branch means the same uniform strain, so the elongation the crosshead sees (less F/C) is
    42/30 of it, as a uniform bar's is (a bar that ignored --lc: about 1). Over the hardening part
    (0.95-0.985 of Fm: 0.4-1.5 mm) single levels scatter ±3 % (a 10 µm crosshead step between
    samples, the two channels read apart); their median is within 2 %."""
    runs = {}
    for name, options in (("lc42", ["--lc", "42", "--l0", "30", "--d0", "6", "--speed", "0.07"]), ("lc30", ["--speed", "0.05"])):
        p = tmp_path / f"{name}.csv"
        code, out, err = run_cli(capsys, "run", "tension", "--quiet", "--time-scale", "60", "--out", p, *options)
        assert_complete_run(code, err, p)
        runs[name] = read_record(p)
    lc42, lc30 = runs["lc42"], runs["lc30"]
    assert lc42.meta["specimen.parallel_length_mm"] == "42.0" and lc42.meta["specimen.l0_mm"] == "30.0"
    assert lc30.meta["specimen.parallel_length_mm"] == "30.0"  # the virtual bar states its own Lc = l0
    fractions = np.linspace(0.95, 0.985, 36)  # past Rp0.2 (0.93 of Fm for steel45), before the flat maximum
    ratio = float(np.median(elongation_at(lc42, fractions) / elongation_at(lc30, fractions)))
    assert ratio == pytest.approx(42.0 / 30.0, rel=0.02)


def test_run_ignores_lc_on_compression_and_says_so(tmp_path, capsys, virtual_runs_on):
    p = tmp_path / "c.csv"
    code, out, err = run_cli(capsys, "run", "compression", "--quiet", "--time-scale", "60", "--target", "0.5", "--out", p, "--lc", "40")
    assert err.startswith("flowcurve: note: --lc ignored: a compression specimen has no such length"), err
    assert "specimen.parallel_length_mm" not in read_record(p).meta


def test_run_compression_response_option_reaches_the_rig_and_the_header(tmp_path, capsys, virtual_runs_on):
    p = tmp_path / "c.csv"
    code, out, err = run_cli(capsys, "run", "compression", "--quiet", "--time-scale", "60", "--out", p, "--compression-response", "slab")
    assert_complete_run(code, err, p)
    rec = read_record(p)
    assert rec.meta["virtual.compression_response"] == "slab" and "compression response slab" in rec.meta["rig.virtual"]
    h0, d0 = float(rec.meta["specimen.h0_mm"]), float(rec.meta["specimen.d0_mm"])
    hk, dmax = float(rec.meta["post.hk_mm"]), float(rec.meta["post.dmax_mm"])
    eps, mu = np.log(h0 / hk), 0.1  # the virtual rig's default friction
    dn = d0 * np.sqrt(h0 / hk)
    seed = 0.0683 * eps**0.83 * (1 - np.exp(-26.7 * mu**1.53))  # (3.18), the slab mirror's barrel
    assert (dmax - dn) / 2 / hk == pytest.approx(seed, abs=3e-5)


def test_response_options_are_refused_with_a_configured_rig(tmp_path, capsys):
    code, _, err = run_cli(capsys, "run", "tension", "--config", tmp_path / "rig.toml", "--quiet", "--d0", "6", "--l0", "30",
                           "--tension-response", "bridgman", "--out", tmp_path / "r.csv")
    assert code == 2 and "--tension-response" in err and "virtual rig in this process" in err and err.count("\n") == 1


def test_demo_passes_both_responses_to_the_rig_and_prints_the_neck_table(tmp_path, capsys, monkeypatch, device_link):
    import flowcurve.demo as demo

    real = demo.run_virtual_test
    monkeypatch.setattr(demo, "run_virtual_test", lambda *args, **kwargs: real(*args, **device_link, **kwargs))
    code, out, err = run_cli(capsys, "demo", "--out", tmp_path, "--quiet", "--tension-response", "bridgman",
                             "--compression-response", "slab")
    for test in ("tension", "compression"):
        assert_complete_run(code, err, tmp_path / "records" / f"{test}.csv")
    assert read_record(tmp_path / "records" / "tension.csv").meta["virtual.tension_response"] == "bridgman"
    assert read_record(tmp_path / "records" / "compression.csv").meta["virtual.compression_response"] == "slab"
    assert "tension response bridgman" in out and "rig response slab" in out
    assert "neck corrections at fracture" in out and "Le Roy et al. (1981)" in out
