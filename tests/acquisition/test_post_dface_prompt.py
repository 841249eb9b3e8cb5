"""The post-test step asks for the original end face (post.dface_mm) on a compression specimen
with h0/d0 ≥ 1.6 — its prompt says it is needed and why, an empty answer is asked once more —
and ``flowcurve annotate`` lists it as still missing there; on a shorter one it stays optional
(issue 37)."""

from __future__ import annotations

from flowcurve.acquisition.procedure import Procedure, TestSpec
from flowcurve.acquisition.stopping import StopCriteria
from flowcurve.cli import main as cli_main
from flowcurve.record.format import read_record


def _run(tmp_path, fake_rig, h0_mm, answers):
    asked, said = [], []
    answers = iter(answers)

    def prompt(text):
        asked.append(text)
        return next(answers)

    s = TestSpec(test="compression", material="fake", geometry_mm={"d0_mm": 6.0, "h0_mm": h0_mm}, speed_mm_per_s=0.05,
                 stop=StopCriteria(target_displacement_mm=0.3))
    proc = Procedure(fake_rig(x_frac_mm=1e9, post=None), s, tmp_path / f"c{h0_mm}.csv", interactive=True, prompt=prompt)
    say = proc.view.say
    proc.view.say = lambda text, *a, **k: (said.append(text), say(text, *a, **k))[1]
    return proc.run(), asked, said


def test_tall_specimen_is_asked_for_the_end_face(tmp_path, fake_rig):
    out, asked, _ = _run(tmp_path, fake_rig, 10.0, ["4.9", "7.1", "6.02"])
    assert len(asked) == 3 and "dface" in asked[2] and "needed" in asked[2] and "optional" not in asked[2]
    assert read_record(out.path).meta["post.dface_mm"] == "6.02"


def test_an_empty_answer_is_asked_once_more_then_named_missing(tmp_path, fake_rig):
    out, asked, said = _run(tmp_path, fake_rig, 10.0, ["4.9", "7.1", "", ""])
    assert len(asked) == 4 and "needed to tell μ" in asked[3]
    assert "post.dface_mm" not in read_record(out.path).meta  # skipped, not invented
    assert any("still missing: post.dface_mm" in t for t in said)


def test_short_specimen_keeps_the_end_face_optional(tmp_path, fake_rig):
    out, asked, said = _run(tmp_path, fake_rig, 7.0, ["3.5", "7.1", ""])
    assert len(asked) == 3 and "(optional)" in asked[2]
    assert not any("still missing" in t for t in said)


def test_annotate_names_the_end_face_missing_on_a_tall_specimen(tmp_path, fake_rig, capsys):
    tall, _, _ = _run(tmp_path, fake_rig, 10.0, ["", "", "", ""])
    short, _, _ = _run(tmp_path, fake_rig, 7.0, ["", "", ""])
    capsys.readouterr()
    assert cli_main(["annotate", str(tall.path), "--set", "post.hk_mm=4.9", "--set", "post.dmax_mm=7.1"]) == 0
    text = capsys.readouterr().out
    assert "still missing: post.dface_mm" in text and "h0/d0 1.67" in text
    assert cli_main(["annotate", str(short.path), "--set", "post.hk_mm=3.5", "--set", "post.dmax_mm=7.1"]) == 0
    assert "still missing" not in capsys.readouterr().out
    assert cli_main(["annotate", str(tall.path), "--set", "post.dface_mm=6.02"]) == 0
    assert "still missing" not in capsys.readouterr().out
