"""Reading an ASF file's sections line by line: ``:units``, ``:root``, ``:bonedata`` and
``:hierarchy`` (other sections are skipped). :func:`motionlang.formats.asf.read_asf` turns
what they declare into a Skeleton; the conventions are in that module's docstring.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError
from motionlang.utils import limits

MAX_ABS = 1e12  # largest magnitude accepted for any number in a file
ROT_DOFS = {"rx": "x", "ry": "y", "rz": "z"}
PARSE_FACTOR = 8  # memory of the lines as Python strings, and more, per byte of file


def read_lines(path: Path) -> list[str]:
    """The lines of a text file (UTF-8, BOM and bad bytes tolerated)."""
    limits.check_file(path, PARSE_FACTOR)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise MotionFormatError(path, f"cannot read file: {exc.strerror or exc}") from None
    return raw.decode("utf-8-sig", errors="replace").splitlines()


def parse_float(tok: str, path, line: int, what: str) -> float:
    """A finite number of at most ``MAX_ABS`` from a token, else MotionFormatError."""
    try:
        v = float(tok)
    except ValueError:
        raise MotionFormatError(path, f"malformed number {tok[:40]!r} in {what}",
                                line=line) from None
    if not math.isfinite(v):
        raise MotionFormatError(path, f"non-finite number {tok!r} in {what}", line=line)
    if abs(v) > MAX_ABS:  # no real length or angle is this big; FK would overflow
        raise MotionFormatError(path, f"number {tok!r} out of range in {what}", line=line)
    return v


def _check_order(order: str, path, line: int) -> str:
    """A rotation order such as ``XYZ`` (upper case), else MotionFormatError."""
    order = order.upper()
    if len(order) != 3 or sorted(order) != ["X", "Y", "Z"]:
        raise MotionFormatError(path, f"bad rotation order {order!r} (want e.g. XYZ)", line=line)
    return order


class AsfBone:
    """One ``begin``/``end`` block of ``:bonedata``, as the file gives it."""

    def __init__(self, line: int):
        self.line = line
        self.name: str | None = None
        self.direction = np.zeros(3)
        self.length = 0.0
        self.axis = np.zeros(3)
        self.order = "XYZ"
        self.dofs: list[str] = []
        self.limits: list[tuple[float, float]] = []


_LIMIT = re.compile(r"\(\s*([^\s()]+)\s+([^\s()]+)\s*\)")


def _limits(text: str, path, line: int) -> list[tuple[float, float]]:
    """``(lo hi)`` pairs on one line (``inf`` allowed: some ASFs leave DOFs unbounded)."""
    body = text.strip()
    if body.lower().startswith("limits"):
        body = body[6:]
    pairs = _LIMIT.findall(body)
    if not pairs or _LIMIT.sub("", body).strip():
        raise MotionFormatError(path, f"malformed limits {body.strip()[:40]!r}", line=line)
    out = []
    for lo, hi in pairs:
        try:
            a, b = float(lo), float(hi)
        except ValueError:
            raise MotionFormatError(path, f"malformed limits ({lo[:20]} {hi[:20]})",
                                    line=line) from None
        if math.isnan(a) or math.isnan(b) or a > b:
            raise MotionFormatError(path, f"bad limits ({lo[:20]} {hi[:20]})", line=line)
        out.append((a, b))
    return out


# ------------------------------------------------------------------------------ sections
class AsfSections:
    """What the sections of one ASF file declare, gathered line by line."""

    def __init__(self, path: Path):
        self.path = path
        self.max_bones = limits.current().max_joints - 1  # the root is a node too
        self.length_scale, self.deg = 1.0, True
        self.root_order = ["TX", "TY", "TZ", "RX", "RY", "RZ"]
        self.root_axis, self.root_orient = "XYZ", np.zeros(3)
        self.bones: dict[str, AsfBone] = {}
        self.children: dict[str, list[str]] = {}
        self.parent_of: dict[str, str] = {}
        self.bone: AsfBone | None = None
        self.hier_seen = False

    def feed(self, lines: list[str]) -> None:
        """Parse every line, sending each to its section's handler."""
        handlers = {":units": self._units, ":root": self._root,
                    ":bonedata": self._bonedata, ":hierarchy": self._hierarchy}
        section = None
        for ln, text in enumerate(lines, start=1):
            tok = text.split("#", 1)[0].split()
            if not tok:
                continue
            key = tok[0].lower()
            if key.startswith(":"):
                if self.bone is not None:
                    raise MotionFormatError(self.path, "section starts inside an unfinished bone",
                                            line=ln)
                section = key
                self.hier_seen |= key == ":hierarchy"
            elif section in handlers:  # other sections (:name, :documentation...) are ignored
                handlers[section](key, tok, text, ln)
        if self.bone is not None:
            raise MotionFormatError(self.path, "file ends inside a bone (missing 'end')",
                                    line=len(lines))
        if not self.hier_seen:
            raise MotionFormatError(self.path, "no :hierarchy section", line=len(lines))

    def _units(self, key: str, tok: list[str], text: str, ln: int) -> None:
        """A ``:units`` line: the length scale and the angle unit."""
        path = self.path
        if key == "length" and len(tok) > 1:
            self.length_scale = parse_float(tok[1], path, ln, "units length")
            if self.length_scale <= 0:
                raise MotionFormatError(path, "units length must be positive", line=ln)
        elif key == "angle" and len(tok) > 1:
            if tok[1].lower() not in ("deg", "rad"):
                raise MotionFormatError(path, f"unknown angle unit {tok[1]!r}", line=ln)
            self.deg = tok[1].lower() == "deg"

    def _root(self, key: str, tok: list[str], text: str, ln: int) -> None:
        """A ``:root`` line: channel order, axis order, orientation."""
        path = self.path
        if key == "order":
            self.root_order = [t.upper() for t in tok[1:]]
            if sorted(self.root_order) != sorted(["TX", "TY", "TZ", "RX", "RY", "RZ"]):
                raise MotionFormatError(path, f"unsupported root order {tok[1:]}", line=ln)
        elif key == "axis":
            self.root_axis = _check_order(tok[1] if len(tok) > 1 else "", path, ln)
        elif key == "orientation":
            if len(tok) != 4:
                raise MotionFormatError(path, "root orientation needs 3 values", line=ln)
            self.root_orient = np.array([parse_float(t, path, ln, "root orientation")
                                         for t in tok[1:]])

    def _bonedata(self, key: str, tok: list[str], text: str, ln: int) -> None:
        """A ``:bonedata`` line: opens, fills or closes a bone."""
        if key == "begin":
            if self.bone is not None:
                raise MotionFormatError(self.path, "'begin' inside a bone", line=ln)
            self.bone = AsfBone(ln)
        elif self.bone is None:
            raise MotionFormatError(self.path, f"{tok[0][:40]!r} outside begin/end", line=ln)
        elif key == "end":
            self._close_bone(ln)
        else:
            _bone_field(self.bone, key, tok, text, self.path, ln)

    def _close_bone(self, ln: int) -> None:
        """Check the bone an ``end`` closes and file it under its name."""
        path, bone = self.path, self.bone
        if not bone.name:
            raise MotionFormatError(path, "bone without a name", line=ln)
        if bone.limits and len(bone.limits) != len(bone.dofs):
            raise MotionFormatError(path, f"bone {bone.name!r} has {len(bone.dofs)} "
                                          f"DOFs but {len(bone.limits)} limits", line=ln)
        if bone.name in self.bones or bone.name == "root":
            raise MotionFormatError(path, f"duplicate bone name {bone.name!r}", line=ln)
        if len(self.bones) >= self.max_bones:
            limits.check(path, "max_joints", len(self.bones) + 2, "joint count", line=ln)
        self.bones[bone.name] = bone
        self.bone = None

    def _hierarchy(self, key: str, tok: list[str], text: str, ln: int) -> None:
        """A ``:hierarchy`` line: a parent bone followed by its children."""
        if key in ("begin", "end"):
            return
        path, par = self.path, tok[0]
        if par != "root" and par not in self.bones:
            raise MotionFormatError(path, f"unknown parent bone {par!r} in hierarchy", line=ln)
        for child in tok[1:]:
            if child not in self.bones:
                raise MotionFormatError(path, f"unknown bone {child!r} in hierarchy", line=ln)
            if child in self.parent_of:
                raise MotionFormatError(path, f"bone {child!r} has two parents", line=ln)
            self.parent_of[child] = par
            self.children.setdefault(par, []).append(child)


def _bone_field(bone: AsfBone, key: str, tok: list[str], text: str, path, ln: int) -> None:
    """Set the field one line inside ``begin``/``end`` gives a bone."""
    if key == "name" and len(tok) == 2:
        bone.name = tok[1]
    elif key == "direction":
        if len(tok) != 4:
            raise MotionFormatError(path, "direction needs 3 values", line=ln)
        bone.direction = np.array([parse_float(t, path, ln, "direction") for t in tok[1:]])
    elif key == "length":
        if len(tok) != 2:
            raise MotionFormatError(path, "length needs 1 value", line=ln)
        bone.length = parse_float(tok[1], path, ln, "length")
    elif key == "axis":
        if len(tok) != 5:
            raise MotionFormatError(path, "axis needs 3 angles and an order", line=ln)
        bone.axis = np.array([parse_float(t, path, ln, "axis") for t in tok[1:4]])
        bone.order = _check_order(tok[4], path, ln)
    elif key == "dof":
        dofs = [t.lower() for t in tok[1:]]
        bad = [d for d in dofs if d not in ROT_DOFS]
        if bad or len(set(dofs)) != len(dofs):
            raise MotionFormatError(path, f"unsupported or repeated DOFs {tok[1:]} "
                                          "(only rx ry rz are supported)", line=ln)
        bone.dofs = dofs
    elif key == "limits" or key.startswith("("):
        bone.limits += _limits(text.split("#", 1)[0], path, ln)
    elif key in ("id", "bodymass", "cofmass"):
        pass  # ids are not used for linking; masses are not modelled
    else:
        raise MotionFormatError(path, f"unknown bone field {tok[0]!r}", line=ln)


