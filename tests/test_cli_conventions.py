"""The conventions every command shares: help and defaults on every option, ``--threads``,
progress as log lines off a terminal, one output stream under torchrun, ``--out`` of every
``train`` a run folder."""
from __future__ import annotations

import argparse

from motionlang.cli.main import (
    DefaultsHelpFormatter,
    build_parser,
    leaf_parsers,
    main,
    shows_default,
)


def _options():
    """(command, action) for every option of every command."""
    parser = build_parser()
    for leaf in leaf_parsers(parser):
        if leaf is parser:
            continue
        for action in leaf._actions:
            if isinstance(action, (argparse._HelpAction, argparse._SubParsersAction)):
                continue
            yield leaf.prog, action


def _name(action) -> str:
    return action.option_strings[-1] if action.option_strings else action.dest


def test_every_option_has_help_and_shows_its_default():
    """Every option says what it does, and -h shows its default where it has one (not
    None, not False); flags and required options need none."""
    missing_help, missing_default = [], []
    for prog, action in _options():
        if not (action.help or "").strip():
            missing_help.append(f"{prog} {_name(action)}")
        elif shows_default(action):
            text = DefaultsHelpFormatter(prog)._get_help_string(action)
            if "default" not in text.lower():
                missing_default.append(f"{prog} {_name(action)}")
    assert not missing_help, f"options without help: {missing_help}"
    assert not missing_default, f"options whose help hides the default: {missing_default}"


def test_help_text_shows_defaults():
    parser = build_parser()
    train = parser._subparsers._group_actions[0].choices["train"]
    m2l = train._subparsers._group_actions[0].choices["m2l"]
    text = m2l.format_help()
    assert "(default: 20)" in text    # --epochs
    assert "--threads" in text


def test_threads_everywhere_and_validated(capsys):
    for leaf in leaf_parsers(build_parser()):
        if leaf.prog == "motionlang":
            continue
        assert "--threads" in leaf._option_string_actions, leaf.prog
    for bad in ("0", "-1", "two"):
        assert main(["info", "--threads", bad, "x.bvh"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "--threads" in err


def test_default_threads_one_on_a_busy_cpu(monkeypatch):
    from motionlang.cli.threads import MAX_DEFAULT, default_threads
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    assert default_threads(load=1.8, cpus=2) == 1          # busy: near the CPU count
    assert default_threads(load=5.0, cpus=4) == 1
    assert default_threads(load=0.2, cpus=2) == min(2, MAX_DEFAULT)
    assert default_threads(load=0.0, cpus=64) == MAX_DEFAULT
    assert default_threads(load=0.0, cpus=1) == 1
    monkeypatch.setenv("OMP_NUM_THREADS", "3")               # the user's setting wins
    assert default_threads(load=9.0, cpus=2) == 3


def test_threads_reach_torch_and_are_restored(monkeypatch):
    import torch

    import motionlang.cli.main as cli_main
    seen = {}
    before = torch.get_num_threads()
    real = cli_main.build_parser

    def with_spy():   # the real parser, `info` running a spy that reads torch's setting
        p = real()
        for leaf in leaf_parsers(p):
            if leaf.prog == "motionlang info":
                leaf.set_defaults(func=lambda args: seen.setdefault("n", torch.get_num_threads()))
        return p
    monkeypatch.setattr(cli_main, "build_parser", with_spy)
    assert cli_main.main(["info", "--threads", "3", "x.bvh"]) == 3   # the spy's "exit code"
    assert seen["n"] == 3 and torch.get_num_threads() == before


class FakeClock:
    def __init__(self):
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def test_log_progress_prints_when_time_passes_not_per_item(capsys):
    from motionlang.utils.progress import LogProgress
    clock = FakeClock()
    bar = LogProgress(range(600), desc="evaluate", unit="motions", clock=clock)
    for i, _ in enumerate(bar):
        clock.t += 0.1                      # 60 s over the 600 items: two lines, then the end
        if i == 100:
            bar.set_postfix(loss="0.5")
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 3, lines
    assert lines[0].startswith("evaluate: 300/600 motions, 30 s elapsed, ~30 s left")
    assert "loss 0.5" in lines[0]
    assert lines[-1].startswith("evaluate: 600/600 motions, done in 60 s")


def test_log_progress_silent_for_a_short_phase(capsys):
    from motionlang.utils.progress import LogProgress
    clock = FakeClock()
    bar = LogProgress(total=1000, desc="fit", clock=clock)
    for _ in range(1000):
        clock.t += 0.01                     # 10 s in all
        bar.update()
    bar.close()
    assert capsys.readouterr().err == ""


def test_progress_off_a_terminal_is_log_lines(monkeypatch):
    import importlib
    import sys
    pg = importlib.import_module("motionlang.utils.progress")
    monkeypatch.setattr(sys.stderr, "isatty", lambda: False, raising=False)
    assert isinstance(pg.progress(range(3), desc="x"), pg.LogProgress)
    assert not isinstance(pg.progress(range(3), desc="x", disable=True), pg.LogProgress)


def test_only_rank_0_prints_under_torchrun(tiny_motion, tmp_path, monkeypatch, capsys):
    from motionlang.formats import write_motion
    path = tmp_path / "m.bvh"
    write_motion(tiny_motion, path)
    assert main(["info", str(path)]) == 0
    assert capsys.readouterr().out                   # a single process prints
    monkeypatch.setenv("RANK", "1")
    assert main(["info", str(path)]) == 0
    assert capsys.readouterr().out == ""             # rank 1 of torchrun: nothing
    monkeypatch.setenv("RANK", "0")
    assert main(["info", str(path)]) == 0
    assert capsys.readouterr().out                   # rank 0 prints


def test_every_train_out_is_a_run_folder():
    from motionlang.models.registry import families, family
    parser = build_parser()
    trains = [leaf for leaf in leaf_parsers(parser) if leaf.prog.startswith("motionlang train ")]
    kinds = {leaf.prog.split()[-1] for leaf in trains}
    assert kinds <= set(families()) and {"m2l", "l2m", "twostream", "crbm"} <= kinds
    for leaf in trains:
        out = leaf._option_string_actions["--out"]
        model = leaf.prog.split()[-1]
        assert out.metavar == "DIR" and out.default == f"runs/{model}", leaf.prog
        assert "run folder" in out.help and family(model).model_file in out.help


def test_run_folder_names_match_the_registry():
    # what train writes is what every model-reading command picks from a folder
    from motionlang.models.registry import RUN_MODEL_FILES, families
    assert {f.model_file for f in families().values()} <= set(RUN_MODEL_FILES)


def test_every_family_with_a_recipe_is_a_train_command():
    from motionlang.models.registry import kinds_with
    parser = build_parser()
    trains = {leaf.prog.split()[-1] for leaf in leaf_parsers(parser)
              if leaf.prog.startswith("motionlang train ")}
    assert set(kinds_with("recipe")) <= trains


def test_train_m2l_has_no_options_of_the_l2m(capsys):
    # the L2M's data options (root weights, plan means) are not offered to the M2L
    assert main(["train", "m2l", "--data", "d", "--root-weight", "2"]) == 2
    assert "unrecognized arguments: --root-weight" in capsys.readouterr().err
