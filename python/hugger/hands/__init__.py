"""Real hands: presets with manufacturers' dimensions, URDF and MJCF import and export.

``hugger.hands.load("barrett_bh8")`` (a preset), ``load("hand.urdf")``, ``load("hand.xml")``
(URDF or MJCF, told apart by the file's root element) or ``load("hand.json")`` (a hand as in a
trajectory file's ``hand_json``) give a :class:`hugger.Hand`; see docs/hands.md.
"""
from __future__ import annotations

import json
import os
from typing import Any

from ..hand import Hand
from .presets import PRESETS, Preset, preset
from .robot import PALM_KEYWORDS, from_mjcf, from_urdf, grasp_joint_values, kind_of_root, to_mjcf, to_urdf, xml_root

__all__ = ["PRESETS", "Preset", "preset", "from_urdf", "from_mjcf", "to_urdf", "to_mjcf", "grasp_joint_values",
           "load"]


#: The suffixes of the robot description files a hand is read from (URDF or MJCF, by the root element).
ROBOT_SUFFIXES = (".urdf", ".xml", ".mjcf")


def load(spec: str | os.PathLike[str], fixed_joints: dict[str, float] | None = None, palm: str | None = None,
         **kwargs: Any) -> Hand:
    """A hand from a preset name, or a ``.urdf``, ``.xml``/``.mjcf`` or ``.json`` file. An XML
    file is read as URDF or MJCF by its root element (``<robot>`` or ``<mujoco>``), whatever its
    extension. ``palm`` names the palm (a URDF's link, an MJCF's body: ``palm_link`` or
    ``palm_body`` of the reader); ``fixed_joints`` and other keywords go to :func:`from_urdf` /
    :func:`from_mjcf`, and are refused for a preset or a JSON hand, which have no joints to
    hold. ``ValueError`` for an unknown preset, a missing, malformed or unknown file, or an
    unknown extension."""
    text = os.fspath(spec)
    ext = os.path.splitext(text)[1].lower()
    if text in PRESETS or ext == ".json":
        given = [k for k, v in (("fixed_joints (--fixed-joint)", bool(fixed_joints)),
                                ("palm (--palm-link)", palm is not None)) if v] + sorted(kwargs)
        if given:
            what = f"the preset {text!r}" if text in PRESETS else f"the JSON hand {text!r}"
            raise ValueError(f"{', '.join(given)}: for a URDF or MJCF file only; {what} is a whole hand, with no "
                             f"joints or links to choose")
    if text in PRESETS:
        return preset(text)
    if ext not in (*ROBOT_SUFFIXES, ".json"):
        raise ValueError(f"hand {text!r} is neither a preset ({', '.join(PRESETS)}) nor a .urdf, .xml/.mjcf or "
                         f".json file")
    if not os.path.isfile(text):
        raise ValueError(f"hand file {text!r} does not exist")
    if ext in ROBOT_SUFFIXES:
        # The root element says which (a URDF may well be called .xml); a file not well-formed
        # before it goes by its extension, to the reader's own message.
        tag = xml_root(text)
        kind = ("URDF" if ext == ".urdf" else "MJCF") if tag is None else kind_of_root(tag)
        if kind is None:
            raise ValueError(f"hand file {text!r} is neither URDF nor MJCF: its root element is <{tag}>, not "
                             f"<robot> or <mujoco>")
        wrong = next(keyword for other, keyword in PALM_KEYWORDS.items() if other != kind)
        if wrong in kwargs:
            raise ValueError(f"hand file {text!r} is {kind}, whose palm is chosen by {PALM_KEYWORDS[kind]}, not "
                             f"{wrong}")
        if palm is not None:
            if PALM_KEYWORDS[kind] in kwargs:
                raise ValueError(f"palm and {PALM_KEYWORDS[kind]} both name the palm: give one")
            kwargs[PALM_KEYWORDS[kind]] = palm
        read = from_urdf if kind == "URDF" else from_mjcf
        return read(text, fixed_joints=fixed_joints, **kwargs)
    try:
        with open(text, encoding="utf-8") as fh:
            d = json.load(fh)
    except (OSError, ValueError, RecursionError) as exc:  # (nested too deep for the reader)
        raise ValueError(f"hand file {text!r} is not readable JSON ({exc})") from None
    try:
        return Hand.from_dict(d, strict=True)
    except ValueError as exc:  # the hand's checks, named by the file (as the robot files' readers do)
        raise ValueError(f"hand file {text!r}: {exc}") from None
