"""Byte-level edits of a valid file, the building blocks of :func:`.inputs.mutate`:
truncation, flipped bytes, deleted, duplicated, swapped and repeated lines, extreme and
broken numbers, words moved around, MAT element tags given another type or size, and for
XML encoding declarations and DTDs (billion laughs, a quadratic blow-up, external entities).

Every edit is driven by ``choose(n)``, an integer in ``range(n)`` (see :mod:`.inputs`).
"""
from __future__ import annotations

import re
from collections.abc import Callable

Choose = Callable[[int], int]
MAX_GROWTH = 4 << 20  # a file this long is not lengthened further

SPECIAL = [b"1e308", b"-1e308", b"nan", b"NaN", b"inf", b"-inf", b"1e999", b"", b"0x10",
           b"1e-400", b"123456789012345678901234567890", b"1.5.5", b"-", b"{", b"}",
           b"9" * 400, b"9" * 5000, "²".encode(), "١٢".encode(), b"1_000", b"+5", b"-0",
           b"9223372036854775808", b"1e12", b"1e13", b"4e-324"]
ENCODINGS = [b"utf-32", b"UTF-16", b"utf-16-le", b"utf-8", b"latin-1", b"klingon", b"ascii",
             b"shift_jis", b"cp037", b"utf-7", b"", b"x" * 300]
LAUGHS = (b'<!DOCTYPE MMM [<!ENTITY a "aaaaaaaaaa">' + b"".join(
    b'<!ENTITY %s "%s">' % (bytes([98 + i]), b"&%s;" % bytes([97 + i]) * 10) for i in range(8))
    + b"]>")
DTDS = [LAUGHS, b'<!DOCTYPE MMM [<!ENTITY q "' + b"1 " * 20000 + b'">]>',
        b'<!DOCTYPE MMM [<!ENTITY e SYSTEM "file:///etc/passwd">]>',
        b'<!DOCTYPE MMM [<!ENTITY % p SYSTEM "http://127.0.0.1:9/x.dtd"> %p;]>',
        b'<!DOCTYPE MMM SYSTEM "http://127.0.0.1:9/mmm.dtd">',
        b'<!DOCTYPE MMM [<!ENTITY e "0.5">]>']
ENTITY_REFS = [b"&i;", b"&q;", b"&e;", b"&a;", b"&amp;", b"&#0;", b"&#x110000;"]
NUMBER = re.compile(rb"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")
TOKEN = re.compile(rb"[^\s<>=']+")
_DECL = re.compile(rb"^\s*<\?xml[^>]*\?>")


def pick(choose: Choose, seq):
    """One element of ``seq``, chosen by ``choose``."""
    return seq[choose(len(seq))]


def edit(data: bytes, op: str, choose: Choose) -> bytes:
    """``data`` with one edit of kind ``op`` ("truncate", "flip", "delete", "duplicate",
    "swap", "repeat", "number", "token", "garbage", "mat-tag", "encoding" or "dtd")."""
    if op == "truncate":
        return data[:choose(len(data) + 1)]
    if op == "flip" and data:
        i = choose(len(data))
        return data[:i] + bytes([choose(256)]) + data[i + 1:]
    if op in ("delete", "duplicate", "swap", "repeat"):
        lines = data.split(b"\n")
        i = choose(len(lines))
        if op == "delete":
            del lines[i]
        elif op == "duplicate":
            lines.insert(i, lines[i])
        elif op == "swap":
            j = choose(len(lines))
            lines[i], lines[j] = lines[j], lines[i]
        elif len(data) < MAX_GROWTH:  # a block of lines repeated: long inputs
            lines[i:i] = lines[i:i + 1 + choose(20)] * pick(choose, [2, 10, 100, 2000])
        return b"\n".join(lines)
    if op in ("number", "token"):
        spans = [m.span() for m in (NUMBER if op == "number" else TOKEN).finditer(data)]
        if not spans:
            return data
        a, b = spans[choose(len(spans))]
        c, d = spans[choose(len(spans))]
        return data[:a] + (pick(choose, SPECIAL) if op == "number" else data[c:d]) + data[b:]
    if op == "garbage":
        i = choose(len(data) + 1)
        return data[:i] + bytes(choose(256) for _ in range(choose(25))) + data[i:]
    if op == "mat-tag":
        return edit_mat_tag(data, choose)
    if op == "encoding":
        return edit_encoding(data, choose)
    if op == "dtd":
        return edit_dtd(data, choose)
    return data


def edit_mat_tag(data: bytes, choose: Choose) -> bytes:
    """A MAT element tag (8-byte aligned after the 128-byte header) with another type or
    size: an uncompressed file's structure, where a flipped byte rarely lands."""
    if len(data) < 136:
        return data
    i = 128 + 8 * choose((len(data) - 128) // 8)
    if choose(2):
        value = choose(20)
    else:
        old = int.from_bytes(data[i + 4:i + 8], "little")
        value = pick(choose, [0, 1, 7, 8, 2 ** 31, 2 ** 32 - 1, old + 8, max(old - 8, 0)])
        i += 4
    return data[:i] + value.to_bytes(4, "little") + data[i + 4:]


def edit_encoding(data: bytes, choose: Choose) -> bytes:
    """Declare an encoding; or write the text in another one, declared or not."""
    body = _DECL.sub(b"", data, count=1)
    decl = b"<?xml version='1.0' encoding='%s'?>" % pick(choose, ENCODINGS)
    how = choose(3)
    if how == 0:
        return decl + body
    codec = pick(choose, ["utf-16", "utf-32", "utf-16-be", "latin-1"])
    text = ((decl if how == 1 else b"") + body).decode("utf-8", errors="replace")
    return text.encode(codec, errors="replace")


def edit_dtd(data: bytes, choose: Choose) -> bytes:
    """Insert a DTD after the XML declaration, maybe with an entity where a number was."""
    m = _DECL.match(data)
    at = m.end() if m else 0
    dtd = pick(choose, DTDS)
    out = data[:at] + dtd + data[at:]
    spans = [s.span() for s in NUMBER.finditer(out, at + len(dtd))]
    if spans and choose(2):
        a, b = spans[choose(len(spans))]
        out = out[:a] + pick(choose, ENTITY_REFS) + out[b:]
    return out
