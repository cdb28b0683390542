"""A decode-time option is stated once: on its family's options field (``L2MOptions``,
``DescribeOptions``), with the command-line flag generated from it; the CLI, the API and the
web app give it no default of their own."""
from __future__ import annotations

import dataclasses
import inspect
import re
from pathlib import Path

from motionlang import api
from motionlang.cli.config_options import given_options, option_fields
from motionlang.cli.main import build_parser
from motionlang.library.options import DescribeOptions
from motionlang.models.seq2seq.config import L2MOptions
from motionlang.models.seq2seq.decode import grounded
from motionlang.web.studio import Studio

SRC = Path(__file__).resolve().parents[1] / "src" / "motionlang"
L2M_FLAGS = [f.name for f in option_fields(L2MOptions)]


def _sub(name: str):
    parser = build_parser()
    action = next(a for a in parser._actions if hasattr(a, "choices") and a.choices
                  and name in a.choices)
    return action.choices[name]


def test_generate_flags_are_the_l2m_options_fields_and_default_to_them():
    assert set(L2M_FLAGS) >= {"width", "method", "temperature", "length_norm", "rerank"}
    args = _sub("generate").parse_args(["a person walks", "-o", "x.bvh"])
    # a flag not given is not an option given: the field's default (or the model's spec) holds
    assert given_options(L2MOptions, args) == {}
    args = _sub("generate").parse_args(["a person walks", "-o", "x.bvh", "-w", "3",
                                        "--temperature", "0.5", "--length-norm"])
    assert given_options(L2MOptions, args) == {"width": 3,
                                               "temperature": 0.5, "length_norm": True}


def test_the_api_and_the_web_app_give_no_decode_default_of_their_own():
    sig = inspect.signature(api.generate_hypotheses)
    assert not set(L2M_FLAGS) & set(sig.parameters)   # they come in **options
    assert any(p.kind is p.VAR_KEYWORD for p in sig.parameters.values())
    web = inspect.signature(Studio.generate).parameters
    assert all(web[n].default is None for n in L2M_FLAGS if n in web)
    for path in ("api.py", "cli/describe_generate.py", "web/studio.py"):
        text = (SRC / path).read_text(encoding="utf-8")
        for name in ("temperature", "length_norm", "rerank"):
            assert not re.search(rf"\b{name}\s*(:|=)", text), f"{path} states {name}"


def test_describe_defaults_are_the_describe_options_fields():
    args = _sub("describe").parse_args(["x.bvh"])
    for f in option_fields(DescribeOptions):
        assert getattr(args, f.name) == f.default, f.name
    assert inspect.signature(api.describe).parameters["width"].default is None
    assert not {"length_penalty", "rank", "raw"} & set(inspect.signature(api.describe).parameters)
    assert inspect.signature(Studio.describe).parameters["width"].default is None
    # the family's describer takes the beam's options from the caller, with no default
    params = inspect.signature(grounded.describe).parameters
    for name in ("width", "length_penalty", "rank"):
        assert params[name].default is inspect.Parameter.empty, name


def test_the_field_defaults_are_what_the_docs_say():
    d = {f.name: f.default for f in dataclasses.fields(DescribeOptions)}
    assert d["width"] == 5 and d["rank"] == "mbr"
    o = L2MOptions()
    assert (o.width, o.method, o.temperature, o.length_norm, o.rerank) == (1, None, 1.0,
                                                                         False, None)
    readme = (SRC.parents[1] / "README.md").read_text(encoding="utf-8")
    assert "likeliest first" not in readme   # describe ranks by MBR unless --rank logp
