"""Command-line pieces the benchmark scripts share."""
from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence


def split_names(text: str) -> list[str]:
    """The names of a comma-separated list: blanks trimmed, empty ones and repeats dropped, order kept."""
    return list(dict.fromkeys(s.strip() for s in text.split(",") if s.strip()))


def comma_names(allowed: Sequence[str], what: str) -> Callable[[str], list[str]]:
    """An argparse ``type``: a comma-separated list of names, each one of ``allowed`` (repeats
    dropped, order kept). Anything else is refused, naming it and the names allowed: argparse's
    one-line error, exit 2."""
    def parse(text: str) -> list[str]:
        chosen = split_names(text)
        unknown = [s for s in chosen if s not in allowed]
        if unknown or not chosen:
            raise argparse.ArgumentTypeError(
                f"unknown {what}: {', '.join(unknown) or '(none given)'} (choose from {', '.join(allowed)})")
        return chosen
    return parse
