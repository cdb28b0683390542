"""Print (or with --check, compare) the SHA-256 of every packaged model file against
``motionlang.models.registry.PACKAGED_SHA256``: after retraining a packaged model, paste
the printed table into the registry. Exit 1 with --check when they differ.

    python scripts/packaged_digests.py [--check]
"""
from __future__ import annotations

import argparse
import sys

from motionlang.models import registry


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if a digest differs")
    args = ap.parse_args(argv)
    rows, stale = [], []
    for name, p in registry.PACKAGED.items():
        got = registry.file_sha256(p.path) if p.path.is_file() else None
        rows.append(f'    "{name}": "{got or "MISSING"}",')
        if got != p.sha256:
            stale.append(name)
    print("PACKAGED_SHA256: dict[str, str] = {\n" + "\n".join(rows) + "\n}")
    if stale:
        print(f"differs from the registry: {', '.join(stale)}", file=sys.stderr)
    return 1 if args.check and stale else 0


if __name__ == "__main__":
    sys.exit(main())
