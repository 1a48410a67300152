"""``skinny trajectory list``: every source of a movement, in two columns (a name, what it
is) whose widths come from the names, so a long name never pushes its row out of line.

The named movements are measured (``get``) on every body, the shipped clips counted from
their files, and the generated kinds' keys and defaults read from the code that parses
them, so the list says what the loaders accept.
"""

from __future__ import annotations

import shutil
import textwrap
from collections.abc import Iterable
from pathlib import Path

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.trajectories import SAMPLE_ASF, SAMPLE_CLIPS, get, names, sample_clip
from skinny_mj.trajectories.asf_amc import CMU_FPS
from skinny_mj.trajectories.babble import BABBLE_KEYS
from skinny_mj.trajectories.library import SET_PREFIX
from skinny_mj.trajectories.patterns import PATTERNS, PREFIX

#: What each fixed movement is (paper B's patterns are described from their parameters).
ABOUT = {
    "ymca": "the YMCA dance, synthesized: key poses joined by minimum-jerk moves with holds",
    "ymca-smooth": "the same as ymca, by a name that says it is the smooth one",
    "ymca-recorded": "a recorded-like YMCA: a person's performance captured as markers "
                     "(never still, tremor, marker noise)",
    "ymca-recorded-unit2d": "ymca-recorded with the 2D targets normalized to unit length "
                            "per frame (the other reading of the thesis's 2D signals)",
    "y": "the Y, then back to the start",
    "y-pure": "y with every elbow held at its starting angle",
    "ym": "Y and M, then back to the start",
    "mirror-right": "both arms do the right arm's part of ymca",
    "mirror-left": "both arms do the left arm's part of ymca",
}
#: Widest name column before a long name gets a line of its own.
MAX_NAME = 30


def _width() -> int:
    return max(60, min(100, shutil.get_terminal_size((100, 24)).columns))


def columns(rows: Iterable[tuple[str, str]], width: int, indent: int = 2) -> list[str]:
    """``(name, description)`` rows as two columns: the name column as wide as its longest
    name (at most :data:`MAX_NAME`; a longer name stands on its own line, its description
    below it), each description wrapped to ``width`` characters."""
    rows = list(rows)
    name_width = min(MAX_NAME, max((len(n) for n, _ in rows), default=0))
    pad = " " * (indent + name_width + 2)
    out = []
    for name, text in rows:
        wrapped = textwrap.wrap(text, max(20, width - len(pad)), break_long_words=False,
                                break_on_hyphens=False)
        if len(name) > name_width:
            out.append(" " * indent + name)
            out += [pad + line for line in wrapped]
        else:
            first, *rest = wrapped or [""]
            out.append(f"{' ' * indent}{name:<{name_width}}  {first}".rstrip())
            out += [pad + line for line in rest]
    return out


def _heading(text: str, width: int) -> list[str]:
    return textwrap.wrap(text, width, subsequent_indent="  ", break_on_hyphens=False)


def _pattern_about(name: str) -> str:
    p = PATTERNS[name.removeprefix(PREFIX)]
    parts = [f"the lagging arm {p.phase_deg:g} deg behind" if p.phase_deg else "in phase"]
    if p.frequency_ratio != 1:
        parts.append(f"leading:lagging frequency {p.leader_cycles}:{p.lagger_cycles}")
    if p.amplitude_ratio != 1:
        parts.append(f"the lagging arm's amplitude {p.amplitude_ratio:g}x the leading one's")
    return "paper B: both arms raised and lowered, " + ", ".join(parts)


def _named_rows() -> list[tuple[str, str]]:
    rows = []
    for name in names():
        bodies = []
        duration = steps = None
        for which in body.body_names():
            try:
                traj = get(name, which)
            except SkinnyInputError:
                continue
            bodies.append(which)
            steps, duration = len(traj), traj.duration_s
        about = ABOUT.get(name) or _pattern_about(name)
        rows.append((name, f"{', '.join(bodies)}; {steps} steps, {duration:.2f} s; "
                           f"{about}"))
    return rows


def _frames(path: Path) -> int:
    """Frames of an Acclaim .amc: each starts with a line holding its number alone."""
    with open(path) as f:
        return sum(1 for line in f if line.strip().isdigit())


def list_text(width: int | None = None) -> str:
    """The whole list, each line at most ``width`` characters (default: the terminal's,
    between 60 and 100) unless a name alone is longer."""
    width = width or _width()
    lines = _heading("Named movements (NAME; NAME@0.5 or --speed 0.5 plays it at half speed, "
                     "--reps N repeats it):", width)
    lines += columns(_named_rows(), width)
    lines += ["", *_heading(f"Shipped motion capture (CMU subject 05, modern dance, "
                            f"{CMU_FPS:g} Hz; a bare name or the path; retargeted onto "
                            "any body by joint angles):", width)]
    frames = {clip: _frames(sample_clip(clip)) for clip in SAMPLE_CLIPS}
    lines += columns([(f"{clip}.amc", f"{n} frames, {n / CMU_FPS:.2f} s; skeleton "
                       f"{SAMPLE_ASF.name}, beside it, so no --asf is needed")
                      for clip, n in frames.items()], width)
    lines += ["", "Files (a path):"]
    lines += columns([
        ("FILE.npz, FILE.csv", "joint angles over time (`skinny trajectory export` writes "
                               "them)"),
        ("FILE.amc --asf SUBJECT.asf", "Acclaim motion capture, any CMU subject (without "
                                        "--asf: the single .asf beside the .amc)"),
        ("FILE.bvh", "BVH motion capture"),
        ("FILE@start=S,duration=D", "an excerpt of any file above, in seconds: "
                                    "md_02.amc@start=3,duration=6.26"),
        ("ANY@feasible[=MARGIN]", "any movement (a name or a file) re-timed along its "
                                  "own path for the body's torque twin: as fast as "
                                  "shipped where the "
                                  "torque limits allow, slower where not (at most MARGIN, "
                                  "default 0.9, of a limit): md_02.amc@feasible"),
    ], width)
    lines += ["", "Generated:"]
    lines += columns([
        ("babble:seed=3,duration=20", "motor babbling: minimum-jerk moves between random "
         "targets over every joint's whole range; keys and defaults "
         + ", ".join(f"{k}={v:g}" for k, v in BABBLE_KEYS.items()) + " (seed; "
         "seconds; peak speeds, rad/s; chances of a move to a joint limit and of a rest); "
         "`babble` alone takes the defaults"),
        (f"{SET_PREFIX}A+B+...", "a training set: the pieces (any names, files or "
         f"babbling above) joined by slow minimum-jerk bridges, e.g. "
         f"{SET_PREFIX}ymca+babble:seed=1+md_03.amc"),
    ], width)
    return "\n".join(lines)
