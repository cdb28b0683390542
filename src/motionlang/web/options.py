"""Options of ``motionlang serve``, torch- and web-library-free (``--help`` reads them).

Each field with a ``help`` is an option (``cli.config_options``); the checks are here.
"""
from __future__ import annotations

import ipaddress
from dataclasses import dataclass, field
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.utils.checks import check_numbers

#: what ``motionlang serve --help`` says it is
SUMMARY = ("a local web app: sentences to motion played in 3D, downloads (BVH, GLB, MP4) on "
           "your own rig, motion files described, an index searched; models load once")
#: text-to-motion models the page offers unless ``--model`` names others
DEFAULT_MODELS = ("l2m", "masked", "twostream", "l2m-procedural")


def _opt(default: Any, help_: str, **meta: Any) -> Any:
    return field(default=default, metadata={"help": help_, **meta})


@dataclass
class ServeOptions:
    """How the app is served and what it loads.

    Attributes:
        host: address to bind; 127.0.0.1 keeps the app to this machine.
        port: TCP port (0: any free one).
        model: text-to-motion models offered in the page (packaged names, checkpoints or
            run folders), each loaded once at start; None: :data:`DEFAULT_MODELS`, those
            that are installed.
        describe_model: the model that describes uploaded motions (an M2L).
        index: an index file (``motionlang index``) to search from the page, or None.
        max_upload_mb: the largest upload (all files of one request together), MiB.
        max_describe_minutes: the longest uploaded take described (a small file can claim
            hours: its frame time is its own), minutes of motion.
        warm: generate one sentence with each model at start, so that the first request
            pays no lazy loading (a sentence encoder is read on first use).
    """

    host: str = _opt("127.0.0.1", "address to bind (another than 127.0.0.1 opens the app "
                                  "to the network: it has no login)", metavar="ADDR")
    port: int = _opt(8000, "TCP port (0: any free one)")
    model: list[str] | None = _opt(None, "a text-to-motion model offered in the page "
                                         "(packaged name, checkpoint or run folder); repeat "
                                         "for several (default: " + ", ".join(DEFAULT_MODELS)
                                   + ", those installed)", append=True, metavar="MODEL")
    describe_model: str = _opt("m2l", "the model that describes uploaded motions",
                               metavar="MODEL")
    index: str | None = _opt(None, "an index file (motionlang index) to search from the page",
                             metavar="FILE")
    max_upload_mb: float = _opt(64.0, "largest upload of one request, MiB (the readers' "
                                      "MOTIONLANG_MAX_* limits apply as well)", metavar="MB")
    max_describe_minutes: float = _opt(30.0, "longest uploaded take the page describes, "
                                             "minutes of motion (its work holds the models: "
                                             "longer ones go to motionlang describe FILE)",
                                       metavar="MIN")
    warm: bool = True

    def __post_init__(self) -> None:
        check_numbers("ServeOptions", self, positive=("max_upload_mb", "max_describe_minutes"))
        if not 0 <= self.port <= 65535:
            raise MotionlangError(f"ServeOptions.port must be in 0..65535, got {self.port}")
        if not self.host.strip():
            raise MotionlangError("ServeOptions.host is empty")

    @property
    def local(self) -> bool:
        """Whether ``host`` is a loopback address (only this machine can connect)."""
        try:
            return ipaddress.ip_address(self.host).is_loopback
        except ValueError:   # a host name
            return self.host == "localhost"

    @property
    def max_upload_bytes(self) -> int:
        return int(self.max_upload_mb * (1 << 20))
