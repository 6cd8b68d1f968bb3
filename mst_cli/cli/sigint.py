"""Knowing that a SIGINT came, for the interrupts Python does not deliver as KeyboardInterrupt
(a Ctrl-C inside an extension module's initialisation comes back as an ImportError)."""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from typing import Any


class SigintSeen:
    """Python's own SIGINT handler (KeyboardInterrupt), which also notes that a SIGINT came. Only
    installed over the default handler: a SIGINT inherited as ignored (nohup) stays ignored."""

    def __init__(self) -> None:
        self.seen = False

    def __call__(self, signum: int, frame: Any) -> None:
        self.seen = True
        signal.default_int_handler(signum, frame)

    @classmethod
    @contextlib.contextmanager
    def installed(cls) -> Iterator[SigintSeen]:
        """The handler installed for the block; an ImportError raised after a SIGINT came is
        raised as the KeyboardInterrupt it was (OCP, under build123d, turns one inside its
        initialisation into "ImportError: initialization failed")."""
        handler = cls.install()
        try:
            yield handler
        except ImportError:
            if not handler.seen:
                raise
            raise KeyboardInterrupt from None

    @classmethod
    def install(cls) -> SigintSeen:
        handler = cls()
        in_main_thread = threading.current_thread() is threading.main_thread()  # signal.signal's rule
        if in_main_thread and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            signal.signal(signal.SIGINT, handler)
        return handler
