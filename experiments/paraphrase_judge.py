"""Words a model has never seen: text-to-motion models asked the Bandai test sentences with
their words swapped for synonyms outside the packaged vocabulary (issue #24: "a pretrained
sentence encoder so that unseen words land near known ones - measure it").

    OMP_NUM_THREADS=1 .venv/bin/python experiments/paraphrase_judge.py \
        --model l2m --model twostream [--data ../shared/data/bandai] [--limit N]
    (the L2M without reading unknown words as known ones: --model nomap=l2m:map_words=false)

Each model generates one motion per Bandai test take from its sentence (as
``motionlang evaluate-judge`` does, feet locked as ``generate`` writes them) and from the same
sentence with :data:`SYNONYMS` applied; the packaged judge says how often it sees the asked
action and style in each. The L2M reads an unseen word as the nearest word it knows where
one is near enough (``models.word_map``), or with ``map_words=false`` as one unknown-word
token; the two-stream model reads sentences through MiniLM (a pretrained language model),
which has seen the synonyms. Prints a Markdown table and how many sentences the swap changed.
Non-commercial: the judge and the Bandai sentences are CC BY-NC 4.0.
"""
from __future__ import annotations

import argparse
import re
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: a word of the Bandai sentences -> a synonym the packaged L2M's 276-word vocabulary lacks
SYNONYMS = {
    "walks": "strolls", "walking": "strolling", "runs": "races", "running": "racing",
    "person": "individual", "human": "individual", "woman": "lady", "man": "gentleman",
    "happily": "gleefully", "happy": "glad", "joyfully": "gleefully", "cheerfully": "merrily",
    "sad": "miserable", "sadly": "miserably", "unhappy": "miserable",
    "tired": "fatigued", "tiredly": "drowsily", "exhausted": "fatigued",
    "angry": "irate", "angrily": "irately", "furiously": "irately",
    "proud": "arrogant", "proudly": "arrogantly", "old": "aged", "elderly": "aged",
    "quickly": "rapidly", "slowly": "unhurriedly", "raises": "hoists", "punches": "jabs",
    "kicks": "boots", "childishly": "immaturely", "timidly": "meekly", "shyly": "bashfully",
}


def paraphrase(text: str) -> str:
    """``text`` with every word of :data:`SYNONYMS` swapped (case kept lower)."""
    return re.sub(r"[A-Za-z]+", lambda m: SYNONYMS.get(m[0].lower(), m[0]), text)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--model", action="append", required=True, help="[NAME=]MODEL, repeatable")
    p.add_argument("--judge", default="judge")
    p.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "bandai"))
    p.add_argument("--limit", type=int, default=0)
    args = p.parse_args()

    import torch
    torch.set_num_threads(1)
    import motionlang as ml
    from motionlang.evaluation.judge import asked_labels, judge_table, markdown_judge_table
    from motionlang.models.judge.fit import bandai_items, bandai_sentences
    from motionlang.models.t2m import FPS
    from motionlang.utils.progress import progress

    judge = ml.load_model(args.judge, kind="judge")
    real = bandai_items(args.data, "test", fps=FPS)[:args.limit or None]
    sentences = bandai_sentences(args.data, "test")[:args.limit or None]
    swapped = [replace(s, text=paraphrase(s.text)) for s in sentences]
    changed = sum(a.text != b.text for a, b in zip(sentences, swapped))
    print(f"{len(sentences)} test sentences, {changed} changed by the swap; e.g. "
          f"{sentences[0].text!r} -> {swapped[0].text!r}")
    generated = {}
    for spec in args.model:
        # NAME=MODEL; a MODEL may carry options itself ("nomap=l2m:map_words=false")
        name, _, path = spec.partition("=") if "=" in spec.split(":")[0] else ("", "", spec)
        name = name or path
        t2m = ml.text_to_motion(path)
        unknown = sum(bool(t2m.unknown_words(s.text)) for s in swapped)
        print(f"{name}: {unknown} swapped sentences have words outside its vocabulary")
        for tag, batch in (("", sentences), (" (synonyms)", swapped)):
            generated[name + tag] = [t2m.positions21(s.text, max(2, len(it.positions)),
                                                     foot_lock=True)
                                     for s, it in progress(list(zip(batch, real)),
                                                           desc=name + tag, unit="motions")]
    table = judge_table(judge, [it.positions for it in real],
                        [(it.content, it.style) for it in real], FPS, generated,
                        asked_labels(sentences), FPS)
    print(markdown_judge_table(table, f"{len(real)} Bandai test takes, judge {args.judge}"))


if __name__ == "__main__":
    main()
