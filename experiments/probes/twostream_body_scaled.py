"""Joints measured against the body's size: the two-stream package's recipe (procedural corpus
+ Bandai takes, half of every epoch each, mirrored) with every motion scaled to one body size
before the one normaliser is fitted, every epoch scored on the Bandai validation pairs
(``--select-evaluator``).

    OMP_NUM_THREADS=1 .venv/bin/python experiments/probes/twostream_body_scaled.py RUN \\
        --corpus runs/twostream_parts/corpus --evaluator runs/evaluator_bandai [--epochs 3]

Each motion's body-frame joints and root steps are multiplied by ``reference / size``: its
size is the median over frames of the left leg's and the spine's bone lengths
(``twostream_body_sizes.py``), the reference the median size of the Bandai training takes
(their actors' one body), so the model's motions come out on that body whatever the
sentence. Normalised by source, the mix reached the Bandai-only figures but made every
motion in the Bandai takes' statistics; measured against the body's size, the two sources'
spreads of the joints' heights are 1.3 times apart instead of 2.4 (``docs/results/
twostream.md``, "A normaliser per source").
"""
from __future__ import annotations

import sys

from twostream_mix_run import run_probe

CHAIN = (("LH", "LK"), ("LK", "LA"), ("root", "BT"), ("BT", "BLN"), ("BLN", "BUN"))


def body_scaled(data, reference_source: int = 1):
    """``data`` (one normaliser) with every motion scaled to the median body size of
    ``reference_source``'s training motions and a normaliser refitted on them."""
    import numpy as np

    from motionlang.features.joint_map import KIT21_NAMES
    from motionlang.features.normalizer import Normalizer
    from motionlang.features.positions import N_LOCAL, local_joints
    at = {n: i for i, n in enumerate(KIT21_NAMES)}
    shared = data.features.normalizer
    raw = {i: shared.inverse(np.asarray(x, dtype=np.float64)) for i, x in data.sequences.items()}

    def size(r):
        j = local_joints(r)
        return float(np.median(sum(np.linalg.norm(j[:, at[u]] - j[:, at[v]], axis=-1)
                                   for u, v in CHAIN)))

    sizes = {i: size(r) for i, r in raw.items()}
    ref = float(np.median([sizes[i] for i in data.splits["train"]
                           if data.sources.get(i) == reference_source]))
    gain = np.zeros(shared.mean.shape)
    gain[:N_LOCAL + 2] = 1.0   # the local joints and the root's steps scale, the turn does not

    def scaled(rid, r):
        return r * (1.0 + gain * (ref / sizes[rid] - 1.0))

    fitted = Normalizer(names=shared.names, min_std=shared.min_std).fit(
        [scaled(i, raw[i]) for i in data.splits["train"]])
    data.sequences = {i: fitted.transform(scaled(i, r)).astype(np.float32) for i, r in raw.items()}
    for part in data.items.values():
        for it in part:
            if it.get("mirrored"):   # a mirrored motion has its motion's bones
                back = shared.inverse(np.asarray(it["motion"], dtype=np.float64))
                it["motion"] = fitted.transform(scaled(it["id"], back)).astype(np.float32)
            else:
                it["motion"] = data.sequences[it["id"]]
    data.features.normalizer = fitted
    print(f"body sizes scaled to {ref:.3f} m; joints' heights spread "
          f"{float(np.median(fitted.std[1:N_LOCAL:3])):.4f} (was "
          f"{float(np.median(shared.std[1:N_LOCAL:3])):.4f})", flush=True)
    return data


def main(argv: list[str] | None = None) -> int:
    def patch(items) -> None:
        built = items.build_twostream_data

        def build(*args, **kw):
            data = built(*args, **kw)
            return body_scaled(data) if len(set(data.sources.values())) > 1 else data

        items.build_twostream_data = build

    return run_probe(__doc__, "twostream_body_scaled.py", argv, patch)


if __name__ == "__main__":
    sys.exit(main())
