"""How a recording looks in the rerun viewer: series styles and the default blueprint.

Per arm, one plot per quantity with one colour per joint (the same colour for a joint in
every plot): the joint angles (deg; thick = actual, thin and lighter = desired), the
command on its own axis (normalized: +-1 is the full scale, the torque limit on the
torque body) and, on the torque body, the torques in N m (thick = applied, thin and
lighter = the bias torque, gravity plus velocity terms; the axis fits the applied torque
and 95 % of the bias samples). The arms sit side by side; the
time axis runs 30 % past the movement's end so the legend (top right) covers no data.
The limits stay in the recording (``/torques/<dof>/limit_*``) but are not drawn in N m:
they would squash the traces; the command plot shows them as +-1.

:func:`read_layout` and :func:`read_styles` read the saved blueprint and the series styles
back from a recording with rerun's own reader, so the look can be checked without a viewer.
"""

from __future__ import annotations

import uuid
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body

DESIRED_RGB = (40, 120, 230)
ACTUAL_RGB = (240, 120, 30)
SENSED_RGB = (150, 150, 150)
COMMAND_RGB = (90, 170, 90)
TORSO_RGB = (170, 170, 170)
ROLE_RGB = {"desired": DESIRED_RGB, "actual": ACTUAL_RGB, "sensed": SENSED_RGB,
            "command": COMMAND_RGB}
#: One colour per joint (both arms alike), none of them the pose's blue or orange.
JOINT_RGB = {"shoulder_abduction": (235, 75, 75), "shoulder_flexion": (70, 200, 110),
             "shoulder_rotation": (175, 110, 245), "elbow_flexion": (240, 205, 40)}
JOINT_LABEL = {"shoulder_abduction": "abduction", "shoulder_flexion": "flexion",
               "shoulder_rotation": "rotation", "elbow_flexion": "elbow"}
THICK, THIN = 2.5, 1.0
ANGLES_TITLE = "joint angles (deg); thick actual, thin desired"
TORQUES_TITLE = "torque (N m); thick applied, thin bias"
#: The time axis ends this far past the last sample, leaving room for the legend.
AXIS_MARGIN = 1.3
#: The 3D view's eye (world m): in front of Skinny, level with his chest, looking at the
#: middle of what the arms can reach (x within +-0.76 m, z 0.87 .. 1.93 m at the wrists).
FRONT_EYE_M = (0.0, -3.6, 1.45)
LOOK_TARGET_M = (0.0, 0.0, 1.35)


def split_dof(name: str) -> tuple[str, str]:
    """``right_elbow_flexion`` -> (``right``, ``elbow_flexion``); no side: ("", name)."""
    side, _, joint = name.partition("_")
    return (side, joint) if side in body.SIDES and joint else ("", name)


def dof_entity(name: str) -> str:
    """Entity of DOF ``name``'s angle series: ``/skinny/<side>/<joint>``."""
    side, joint = split_dof(name)
    return f"/skinny/{side}/{joint}" if side else f"/skinny/{name}"


def joint_rgb(name: str, light: bool = False) -> tuple[int, int, int]:
    """The colour of DOF ``name``'s joint; ``light``: halfway to white (a reference)."""
    rgb = JOINT_RGB.get(split_dof(name)[1], SENSED_RGB)
    return tuple(round(c + (255 - c) * 0.5) for c in rgb) if light else rgb


def joint_label(name: str) -> str:
    joint = split_dof(name)[1]
    return JOINT_LABEL.get(joint, joint)


def series_style(dof: str, role: str) -> tuple[str, tuple[int, int, int], float]:
    """Legend name, colour and width of DOF ``dof``'s series ``role``. The thick and thin
    series of a joint share its name, so the legend lists each joint once."""
    thin = role in ("desired", "gravity", "commanded", "limit_upper", "limit_lower")
    return joint_label(dof), joint_rgb(dof, light=thin), THIN if thin else THICK


def torque_spans(dof_names: Sequence[str], torques: Mapping[str, np.ndarray]
                 ) -> dict[str, float]:
    """Per arm, the half-height of its torque plot (N m): 1.15 x the larger of the largest
    applied torque and the 95th percentile of the bias torque, whose spikes (the
    velocity terms of fast moves) would otherwise squash the applied traces."""
    applied = np.abs(np.asarray(torques["applied_nm"], float))
    bias = np.abs(np.asarray(torques["gravity_nm"], float))
    spans = {}
    for side in body.SIDES:
        idx = [i for i, n in enumerate(dof_names) if split_dof(n)[0] == side]
        if idx:
            top = max(applied[:, idx].max(), np.percentile(bias[:, idx], 95))
            spans[side] = _labelled_span(1.15 * float(top) if top > 0 else 1.0)
    return spans


def _labelled_span(span: float) -> float:
    """``span`` widened where the plot would label no tick but 0: the viewer labels a
    power of ten only when a few of them fit (a half-range of 6-10 units of 10^k gets
    its labels at 10^(k+1), outside; 1-1.2 units puts them on the edge)."""
    unit = 10.0 ** np.floor(np.log10(span))
    if span / unit > 6.0:
        return 11.0 * unit
    return max(span, 1.2 * unit)


def blueprint(has_curves: bool, application_id: str, dof_names: Sequence[str],
              duration_s: float, torque_span: Mapping[str, float] | None = None):
    """The default blueprint: the pose (left) and the plots (right); ``torque_span``
    (see :func:`torque_spans`) adds the torque plots of the torque body."""
    import rerun as rr
    import rerun.blueprint as rrb

    def named(item, name: str):
        item.id = uuid.uuid5(uuid.NAMESPACE_URL, f"{application_id}/blueprint/{name}")
        return item

    axis = rrb.archetypes.TimeAxis(view_range=rr.TimeRange(
        start=rr.TimeRangeBoundary.absolute(seconds=0.0),
        end=rr.TimeRangeBoundary.absolute(seconds=duration_s * AXIS_MARGIN)))
    legend = rrb.PlotLegend(corner=rrb.Corner2D.RightTop)

    def plot(key: str, side: str, title: str, entities: list[str], axis_y=None):
        return named(rrb.TimeSeriesView(
            origin="/", contents=[f"+ {e}" for e in entities], name=f"{side} arm: {title}",
            axis_x=axis, axis_y=axis_y, plot_legend=legend), f"{key}-{side}")

    rows = []
    by_side = {s: [n for n in dof_names if split_dof(n)[0] == s] for s in body.SIDES}
    sides = [s for s in body.SIDES if by_side[s]]

    rows.append(named(rrb.Horizontal(*[plot(
        "angles", s, ANGLES_TITLE,
        [f"{dof_entity(n)}/{r}" for n in by_side[s] for r in ("desired", "actual")])
        for s in sides]), "angles"))
    torques = torque_span is not None
    if torques:
        rows.append(named(rrb.Horizontal(*[plot(
            "torques", s, TORQUES_TITLE,
            [f"/torques/{n}/{r}" for n in by_side[s] for r in ("gravity", "applied")],
            axis_y=rrb.archetypes.ScalarAxis(range=(-torque_span[s], torque_span[s])))
            for s in sides]), "torques"))
    scale = "torque limit" if torques else "full scale"
    rows.append(named(rrb.Horizontal(*[plot(
        "command", s, f"command (normalized, ±1 = {scale})",
        [f"{dof_entity(n)}/command" for n in by_side[s]],
        axis_y=rrb.archetypes.ScalarAxis(range=(-1.1, 1.1))) for s in sides]), "command"))
    tabs = [named(rrb.TimeSeriesView(origin="/signals", name="signals", axis_x=axis,
                                     plot_legend=legend), "signals")]
    if has_curves:
        tabs.append(named(rrb.TimeSeriesView(origin="/curves", name="learning curves"),
                          "curves"))
    tabs.append(named(rrb.TextDocumentView(origin="/info", name="info"), "info"))
    rows.append(named(rrb.Tabs(*tabs), "tabs"))
    shares = [3.0, 3.0, 2.0, 2.5] if torques else [3.0, 2.0, 3.0]
    # Without an eye the viewer frames the bounding box from above-behind, zoomed onto
    # the head with the arms off screen; from the front (Skinny faces -y) at a distance
    # that fits both arms fully stretched up and out in the tall, narrow pose panel.
    eye = rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=FRONT_EYE_M,
                            look_target=LOOK_TARGET_M, eye_up=(0.0, 0.0, 1.0))
    pose = named(rrb.Spatial3DView(origin="/pose", name="pose", eye_controls=eye), "pose")
    series = named(rrb.Vertical(*rows, row_shares=shares), "series")
    root = named(rrb.Horizontal(pose, series, column_shares=[2, 5]), "root")
    # The entity tree and the selection start folded (the toggles at the top right open
    # them): the plots get the width. The time panel starts on ``time`` (seconds).
    return rrb.Blueprint(root, rrb.BlueprintPanel(state="collapsed"),
                         rrb.SelectionPanel(state="collapsed"),
                         rrb.TimePanel(state="collapsed", timeline="time"))


# -- reading the look back from a recording ----------------------------------------------
@dataclass(frozen=True)
class SavedView:
    """One view of a recording's saved blueprint, as rerun stores it.

    ``kind`` is rerun's view class (``TimeSeries``, ``3D``, ``TextDocument``); ``query``
    the view's entity filter (``+ /a/b``, ``+ $origin/**``); ``time_range_s`` the time
    axis (s), ``value_range`` the value axis, ``legend`` the legend's corner, ``eye`` the
    3D view's eye (``position``, ``look_target``, ``eye_up`` in world m), each None where
    the blueprint leaves the viewer's default.
    """

    name: str
    kind: str
    origin: str
    query: tuple[str, ...]
    time_range_s: tuple[float, float] | None = None
    value_range: tuple[float, float] | None = None
    legend: str | None = None
    eye: Mapping[str, tuple[float, ...]] | None = None

    def shows(self, entities: Sequence[str]) -> list[str]:
        """Those of ``entities`` the view's query includes: ``+ PATH`` the entity itself,
        ``+ PATH/**`` it and everything under it, ``- ...`` excludes; of the rules that
        match, the most specific decides (an exact path, else the longest subtree), as in
        rerun's entity filter (here without its ``/*`` and properties)."""
        rules = []
        for expr in self.query:
            sign, path = (expr[0], expr[1:].strip()) if expr[:1] in ("+", "-") else ("+", expr)
            path = path.strip().replace("$origin", self.origin.rstrip("/")) or "/"
            if "*" in path.removesuffix("/**"):
                raise ValueError(f"unsupported entity filter {expr!r}")
            rules.append((sign == "+", path))

        def specificity(entity: str, path: str) -> tuple[int, int] | None:
            """(exact?, length of the subtree's root) of a match, None for no match."""
            if not path.endswith("/**"):
                return (1, len(path)) if entity == path else None
            base = path[:-3].rstrip("/")
            inside = not base or entity == base or entity.startswith(base + "/")
            return (0, len(base)) if inside else None

        shown = []
        for entity in entities:
            matched = [(rank, include) for include, path in rules
                       if (rank := specificity(entity, path)) is not None]
            if matched and max(matched)[1]:
                shown.append(entity)
        return shown


@dataclass(frozen=True)
class SavedContainer:
    """A container of the saved blueprint: ``kind`` (``Horizontal``, ``Vertical``,
    ``Tabs``, ``Grid``), its shares and its children (views by name, or containers)."""

    kind: str
    shares: tuple[float, ...]
    children: tuple[SavedContainer | str, ...]


@dataclass(frozen=True)
class SavedLayout:
    """A recording's saved default blueprint: the views by name, the tree of containers
    (``root``), the panels' states (``blueprint_panel``, ``selection_panel``,
    ``time_panel`` -> ``Collapsed``, ...) and the timeline the time panel starts on."""

    views: Mapping[str, SavedView]
    root: SavedContainer
    panels: Mapping[str, str]
    timeline: str | None


def _blueprint_rows(path: str | Path) -> dict[str, dict[str, list]]:
    """Blueprint entity -> {``Archetype:field``: its values} (the latest row of each)."""
    from rerun.chunk import RrdReader

    reader = RrdReader(str(path))
    stores = reader.blueprints()
    if not stores:
        raise SkinnyInputError("holds no blueprint", path=path)
    rows: dict[str, dict[str, list]] = {}
    for chunk in reader.stream(store=stores[0]):
        batch = chunk.to_record_batch()
        order = np.argsort(batch.column("blueprint").to_numpy(), kind="stable")
        for name in batch.schema.names:
            if ":" in name:
                values = batch.column(name).to_pylist()
                rows.setdefault(chunk.entity_path, {})[name] = values[order[-1]]
    return rows


def read_layout(path: str | Path) -> SavedLayout:
    """The default blueprint saved in the recording ``path`` (what the viewer opens on),
    read back with rerun's own reader."""
    import rerun.blueprint as rrb

    rows = _blueprint_rows(path)

    def one(entity: str, field: str, default=None):
        values = rows.get(entity, {}).get(field)
        return values[0] if values else default

    views = {}
    for entity in rows:
        if not entity.startswith("/view/") or entity.count("/") != 2:
            continue
        time_axis = one(f"{entity}/TimeAxis", "TimeAxis:view_range")
        value_axis = one(f"{entity}/ScalarAxis", "ScalarAxis:range")
        corner = one(f"{entity}/PlotLegend", "PlotLegend:corner")
        eye = {k: tuple(one(f"{entity}/EyeControls3D", f"EyeControls3D:{k}"))
               for k in ("position", "look_target", "eye_up")
               if one(f"{entity}/EyeControls3D", f"EyeControls3D:{k}") is not None}
        view = SavedView(
            name=one(entity, "ViewBlueprint:display_name", ""),
            kind=one(entity, "ViewBlueprint:class_identifier", ""),
            origin=one(entity, "ViewBlueprint:space_origin", "/"),
            query=tuple(rows.get(f"{entity}/ViewContents", {}).get("ViewContents:query", ())),
            time_range_s=None if time_axis is None else
            (time_axis["start"] / 1e9, time_axis["end"] / 1e9),
            value_range=None if value_axis is None else tuple(value_axis),
            legend=None if corner is None else rrb.Corner2D(corner).name,
            eye=eye or None)
        views[entity.removeprefix("/")] = view

    def container(ref: str) -> SavedContainer | str:
        if ref.startswith("view/"):
            return views[ref].name
        entity = f"/{ref}"
        shares = (rows[entity].get("ContainerBlueprint:col_shares")
                  or rows[entity].get("ContainerBlueprint:row_shares") or ())
        kind = rrb.components.ContainerKind(one(entity, "ContainerBlueprint:container_kind"))
        return SavedContainer(kind.name, tuple(shares), tuple(
            container(c) for c in rows[entity].get("ContainerBlueprint:contents", ())))

    root = one("/viewport", "ViewportBlueprint:root_container")
    panels = {}
    for panel, field in (("blueprint_panel", "PanelBlueprint:state"),
                         ("selection_panel", "PanelBlueprint:state"),
                         ("time_panel", "TimePanelBlueprint:state")):
        state = one(f"/{panel}", field)
        if state is not None:
            panels[panel] = rrb.components.PanelState(state).name
    return SavedLayout(
        views={v.name: v for v in views.values()},
        root=container(f"container/{uuid.UUID(bytes=bytes(root))}"),
        panels=panels, timeline=one("/time_panel", "TimePanelBlueprint:timeline"))


def read_styles(path: str | Path) -> dict[str, dict[str, Any]]:
    """Every entity's static look in the recording ``path``: entity -> {``colors``:
    [(r, g, b), ...], ``names``, ``widths`` (series), ``radii`` (3D) where logged}."""
    from rerun.chunk import RrdReader

    styles: dict[str, dict[str, Any]] = {}
    for chunk in RrdReader(str(path)).stream():
        if not chunk.is_static:
            continue
        batch = chunk.to_record_batch()
        for name in batch.schema.names:
            archetype, _, field = name.partition(":")
            if field not in ("colors", "names", "widths", "radii"):
                continue
            values = [v for row in batch.column(name).to_pylist() if row for v in row]
            if field == "colors":  # rerun packs 0xRRGGBBAA
                values = [((c >> 24) & 255, (c >> 16) & 255, (c >> 8) & 255) for c in values]
            styles.setdefault(chunk.entity_path, {})[field] = values
    return styles
