"""Research probes on data whose answer is known (``experiments/probes/l2m_context_probe.py``,
``l2m_directions.py``) and the data tool ``scripts/corpus_subset.py`` on a small procedural
corpus."""
from __future__ import annotations

import json

import numpy as np
import pytest

from helpers.scripts import PROBES, SCRIPTS, load_script


def test_probes_find_a_linear_signal_and_no_signal_in_noise():
    probe = load_script(PROBES / "l2m_context_probe.py")
    rng = np.random.default_rng(0)
    x = rng.normal(size=(200, 6))
    assert probe.ridge_r2(x, x @ np.arange(1.0, 7.0)) > 0.99
    assert probe.ridge_r2(x, rng.normal(size=200)) < 0.05
    side = x[:, 2] > 0
    assert probe.probe_accuracy(x, side) > 0.95
    assert probe.probe_accuracy(x, rng.random(200) > 0.5) < 0.65


def test_corpus_subset_links_the_motions_made_only_of_the_given_primitives(tmp_path, capsys):
    from motionlang.datasets.seq2seq_pairs import primitive_labels
    from motionlang.datasets.synth.corpus import write_corpus
    src = tmp_path / "corpus"
    write_corpus(src, 12, seed=3, workers=1, show_progress=False)
    labels = {m.name[:-len("_meta.json")]: primitive_labels(json.loads(m.read_text()))
              for m in src.glob("*_meta.json")}
    first = sorted(labels)[0]
    only = sorted(set(labels[first]))
    want = {k for k, v in labels.items() if set(v) <= set(only) and set(v) != {"stand"}}
    subset = load_script(SCRIPTS / "corpus_subset.py")
    assert subset.main([str(src), str(tmp_path / "sub"), "--only", *only]) == 0
    got = {p.name[:-len("_meta.json")] for p in (tmp_path / "sub").glob("*_meta.json")}
    assert first in got and got == want
    assert all(p.is_symlink() for p in (tmp_path / "sub").iterdir())
    assert len(list((tmp_path / "sub").iterdir())) == 3 * len(want)
    assert f"{len(want)} of 12 motions" in capsys.readouterr().out
    with pytest.raises(SystemExit, match="already exists"):
        subset.main([str(src), str(tmp_path / "sub"), "--only", *only])
    with pytest.raises(SystemExit, match="no motion made only of"):
        subset.main([str(src), str(tmp_path / "none"), "--only", "fly"])
    assert not (tmp_path / "none").exists() and not (tmp_path / "none.partial").exists()


def test_directions_script_measures_the_way_true_motions_go(tmp_path):
    """experiments/probes/l2m_directions.py's measures on true procedural motions: a backward walk goes
    backward, a forward walk forward, and a second leftward sidestep goes left by the sign
    calibrated on the first."""
    from motionlang.datasets.seq2seq_pairs import primitive_labels
    from motionlang.datasets.synth.corpus import write_corpus
    from motionlang.features.angles import AnglesFeatures
    from motionlang.features.frames import motion_frames
    from motionlang.formats.mmm import read_mmm
    directions = load_script(PROBES / "l2m_directions.py")
    root = tmp_path / "corpus"
    write_corpus(root, 40, seed=5, workers=1, show_progress=False)
    motions, by_label = {}, {}
    for meta in sorted(root.glob("*_meta.json")):
        stem = meta.name[:-len("_meta.json")]
        motions[stem] = read_mmm(root / f"{stem}_mmm.xml")
        labels = primitive_labels(json.loads(meta.read_text()))
        if len(labels) == 1:
            by_label.setdefault(labels[0], []).append(stem)
    assert {"walk/backward", "walk/forward"} <= set(by_label) and len(by_label["walk/left"]) >= 2
    fs = AnglesFeatures()
    fs.fit(list(motions.values()))
    left = directions.left_sign(fs, root)
    assert left in (1.0, -1.0)

    def moved(stem):
        return directions.body_frame_distances(fs, motion_frames(fs, motions[stem], 1)[0])
    assert moved(by_label["walk/backward"][0])[1] < -0.5
    assert moved(by_label["walk/forward"][0])[1] > 0.5
    # the calibration read the first "leftwards" sample; the other one must agree
    calibrated = sorted(p.name[:-len("_annotations.json")] for p in root.glob("*_annotations.json")
                        if "leftwards" in p.read_text())[0]
    other = [s for s in by_label["walk/left"] if s != calibrated][0]
    side, forward, _ = moved(other)
    assert left * side > 0.5 and abs(forward) < abs(side)
