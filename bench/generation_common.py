"""Shared pieces of the generation benchmarks: which objects fit the hand, AUC."""
from __future__ import annotations

from pathlib import Path

import numpy as np

import hugger

SHARED_OBJECTS = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "objects"

#: An object fits the 5x5 hand (links 2 cm, palm radius 3 cm; reach 10 cm) when its bounding box
#: is at most 12 cm long, at least 4 cm thin, and its middle extent at least 5 cm: longer objects
#: cannot be wrapped by 10 cm fingers, smaller ones slip between the straight fingers.
FIT_MAX, FIT_MIN, FIT_MID = 0.12, 0.04, 0.05


def fits(obj: hugger.Object) -> bool:
    lo, hi = obj.bounds
    e = np.sort(hi - lo)
    return bool(e[2] <= FIT_MAX and e[0] >= FIT_MIN and e[1] >= FIT_MID)


def object_specs() -> list[str]:
    """Built-in names, then the shared mesh paths (where ../shared is present)."""
    specs = list(hugger.objects.BUILTINS)
    if SHARED_OBJECTS.is_dir():
        specs += [str(p) for p in sorted(SHARED_OBJECTS.glob("*.obj"))]
    return specs


def fitting_objects() -> list[str]:
    """Built-in names and shared mesh paths that fit the default hand."""
    from hugger.scenarios import load_object

    return [s for s in object_specs() if fits(load_object(s)[1])]


def ranking_value(force_closure, firmness) -> float:
    """hugger.search's ranking key (force closure, then firmness) as one number, for AUCs."""
    return 1000.0 * bool(force_closure) + float(firmness)


def auc(scores, labels) -> float:
    """Area under the ROC curve: P(score of a held grasp > score of a lost one), ties count half."""
    s = np.asarray(scores, dtype=np.float64)
    y = np.asarray(labels, dtype=bool)
    pos, neg = s[y], s[~y]
    if len(pos) == 0 or len(neg) == 0:
        return float("nan")
    greater = (pos[:, None] > neg[None, :]).sum()
    ties = (pos[:, None] == neg[None, :]).sum()
    return float((greater + 0.5 * ties) / (len(pos) * len(neg)))
