"""``nodegraph inspect X.rrd``: what a recording file holds, as text — per recording its id and name, the
entity tree (numbered siblings folded into one line), the timelines with their ranges, and the
blueprint's containers and views. For a user who wants to know what to look for in the viewer, and
for notes that quote a recording's layout."""

from __future__ import annotations

import re
import uuid
from collections import defaultdict
from pathlib import Path

_NUMBER = re.compile(r"^\d+$")
CONTAINER_KINDS = {1: "tabs", 2: "horizontal", 3: "vertical", 4: "grid"}  # rerun.blueprint.components.ContainerKind


def describe_rrd(path: Path, depth: int = 6) -> str:
    from rerun.chunk import RrdReader

    reader = RrdReader(str(path))
    lines = [f"{path}: {len(reader.recordings())} recording(s), {len(reader.blueprints())} blueprint(s)"]
    for entry in reader.recordings():
        lines += ["", *_recording(reader, entry, depth)]
    for i, entry in enumerate(reader.blueprints()):
        lines += ["", f"blueprint {i + 1} ({entry.application_id}):", *_blueprint(reader, entry)]
    return "\n".join(lines)


def _recording(reader, entry, depth: int) -> list[str]:
    archetypes: dict[str, set[str]] = defaultdict(set)
    ranges: dict[str, list[int]] = {}
    name = ""
    for chunk in reader.stream(store=entry):
        batch = chunk.to_record_batch()
        if chunk.entity_path == "/__properties":
            if "RecordingInfo:name" in batch.schema.names:
                name = " ".join(v for row in batch.column("RecordingInfo:name").to_pylist() for v in row or [])
            continue
        for column in batch.schema.names:
            if column.startswith("rerun.") or column in chunk.timeline_names:
                continue
            if ":" in column:
                archetypes[chunk.entity_path].add(column.split(":")[0])
            else:  # a property logged with AnyValues (e.g. kind, material): shown with its value
                value = next((v for v in batch.column(column).to_pylist() if v is not None), None)
                shown = value[0] if isinstance(value, list) and len(value) == 1 else value
                archetypes[chunk.entity_path].add(f"{column}={shown}")
        for timeline in chunk.timeline_names:
            values = [v for v in batch.column(timeline).to_pylist() if v is not None]
            if values:
                low, high = ranges.get(timeline, [min(values), max(values)])
                ranges[timeline] = [min(low, min(values)), max(high, max(values))]
    lines = [f"recording {entry.recording_id} ({entry.application_id}): {name or '(no name)'}"]
    lines.append("  timelines: " + (", ".join(f"{t} {a}…{b}" for t, (a, b) in sorted(ranges.items())) or "none"))
    lines.append(f"  entities: {len(archetypes)} with data")
    lines += ["  " + line for line in entity_tree(archetypes, depth)]
    return lines


def entity_tree(archetypes: dict[str, set[str]], depth: int) -> list[str]:
    """The entity paths as an indented tree, with the archetypes (and properties) logged at each entity;
    numbered siblings (``0000`` … ``0312``) fold into one line and only the first is shown below it."""
    tree: dict = {}
    for path in archetypes:
        node = tree
        for part in path.strip("/").split("/"):
            node = node.setdefault(part, {})
    lines: list[str] = []

    def kinds(path: str) -> str:
        found = archetypes.get(path)
        return f"  [{', '.join(sorted(found))}]" if found else ""

    def count(node: dict) -> int:
        return sum(1 + count(child) for child in node.values())

    def walk(node: dict, prefix: str, level: int) -> None:
        names = sorted(node)
        numbered = sorted((n for n in names if _NUMBER.match(n)), key=int)
        if len(numbered) > 2:
            first = numbered[0]
            folded = f"{first}…{numbered[-1]} ({len(numbered)} alike; the first shown)"
            lines.append(f"{'  ' * level}{folded}{kinds(prefix + '/' + first)}")
            names = [n for n in names if n not in numbered]
            show(first, node[first], prefix, level + 1)
        for name in names:
            lines.append(f"{'  ' * level}{name}{kinds(prefix + '/' + name)}")
            show(name, node[name], prefix, level + 1)

    def show(name: str, child: dict, prefix: str, level: int) -> None:
        if not child:
            return
        if level >= depth:
            lines.append(f"{'  ' * level}… {count(child)} entities below")
            return
        walk(child, f"{prefix}/{name}", level)

    walk(tree, "", 0)
    return lines


def _blueprint(reader, entry) -> list[str]:
    fields: dict[str, dict[str, object]] = defaultdict(dict)
    for chunk in reader.stream(store=entry):
        batch = chunk.to_record_batch()
        for column in batch.schema.names:
            if column.startswith(("ContainerBlueprint:", "ViewBlueprint:", "ViewportBlueprint:", "ViewContents:")):
                values = [v for v in batch.column(column).to_pylist() if v is not None]
                if values:
                    fields[chunk.entity_path][column.split(":")[1]] = values[-1]
    roots = [f.get("root_container") for f in fields.values() if "root_container" in f]
    lines: list[str] = []

    def first(value):
        return value[0] if isinstance(value, list) and value else value

    def walk(path: str, level: int) -> None:
        item = fields.get(path, {})
        if path.startswith("/container/"):
            kind = CONTAINER_KINDS.get(first(item.get("container_kind")), "container")
            lines.append(f"{'  ' * level}{first(item.get('display_name')) or '(unnamed)'} [{kind}]")
            for child in item.get("contents") or []:
                walk("/" + str(child).lstrip("/"), level + 1)
        elif path.startswith("/view/"):
            query = fields.get(f"{path}/ViewContents", {}).get("query") or []
            what = " ".join(str(q) for q in query) if isinstance(query, list) else str(query)
            lines.append(
                f"{'  ' * level}{first(item.get('display_name'))} [{first(item.get('class_identifier'))}]"
                f" origin {first(item.get('space_origin'))}" + (f": {what}" if what else "")
            )

    for root in roots:  # the root container's id, as the 16 bytes of a UUID
        walk(f"/container/{uuid.UUID(bytes=bytes(first(root)))}", 1)
    views = sum(1 for path in fields if path.startswith("/view/") and not path.endswith("/ViewContents"))
    containers = sum(1 for path in fields if path.startswith("/container/"))
    return [f"  {containers} containers, {views} views", *lines]
