"""The building of a map file, as the physics robot builds it: `situate map show`'s JSON, read.

The map file is read by the same loader as the 2-D simulator's (``situate._native.map_json``),
so the two simulators run in one building: what the file says, and what `situate map check`
accepts, is what both build.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

#: A wall: ``(x0, y0, x1, y1)``, m.
Segment = tuple[float, float, float, float]


@dataclass(frozen=True)
class Barcode:
    """A barcode: an id at a point, readable from the side it faces (``None``: from anywhere)."""

    id: int
    x: float
    y: float
    facing: float | None


@dataclass(frozen=True)
class Car:
    """An elevator car: its shaft rectangle (the same on every floor), door, panel and barcode."""

    id: int
    x0: float
    y0: float
    x1: float
    y1: float
    door: Segment
    walls: tuple[Segment, ...]
    #: The floor-button panel, where the car's barcode is: ``(x, y, facing)``.
    panel: tuple[float, float, float]
    barcode: int

    def contains(self, x: float, y: float) -> bool:
        """Whether a point is inside the car."""
        return self.x0 < x < self.x1 and self.y0 < y < self.y1


@dataclass(frozen=True)
class Floor:
    """One floor: its walls, obstacles (closed polygons), door openings and barcodes."""

    level: int
    name: str
    walls: tuple[Segment, ...]
    obstacles: tuple[tuple[tuple[float, float], ...], ...]
    doors: tuple[Segment, ...]
    #: Every barcode on the floor: beside doors, on walls, the lobby's and the office's.
    barcodes: tuple[Barcode, ...]
    #: The lobby's call button ``(x, y, facing)``, if the floor has a lobby.
    button: tuple[float, float, float] | None
    #: The office's outline, if the office is on this floor: where a message is delivered.
    office: tuple[tuple[float, float], ...] | None = None

    def obstacle_edges(self) -> list[Segment]:
        """Every edge of every obstacle polygon."""
        out: list[Segment] = []
        for poly in self.obstacles:
            for i, (ax, ay) in enumerate(poly):
                bx, by = poly[(i + 1) % len(poly)]
                out.append((ax, ay, bx, by))
        return out


@dataclass(frozen=True)
class Building:
    """A building: floors, the elevator's cars and timing, the mission (as `Map::mission_json`)."""

    name: str
    robot_radius: float
    floors: tuple[Floor, ...]
    cars: tuple[Car, ...]
    open_s: tuple[float, float]
    mission: dict[str, Any]
    #: The map file it was read from (`load`): the elevator's logic reads it too.
    source: str | None = None

    @staticmethod
    def load(path: str | Path) -> Building:
        """Reads a map file with the 2-D simulator's loader.

        Raises:
            ValueError: the loader's error, naming the file and the line.
        """
        from situate import _native

        return Building.from_json(_native.map_json(str(path)), source=str(path))

    @staticmethod
    def from_json(text: str, source: str | None = None) -> Building:
        """Reads the JSON that `situate map show` prints (`source`: the map file it shows)."""
        j = json.loads(text)

        def seg(s: list[float]) -> Segment:
            return (float(s[0]), float(s[1]), float(s[2]), float(s[3]))

        def barcode(b: dict[str, Any]) -> Barcode:
            facing = b.get("facing")
            return Barcode(int(b["id"]), float(b["x"]), float(b["y"]), _opt_float(facing))

        floors = []
        for f in j["floors"]:
            codes = [barcode(b) for b in f["barcodes"]]
            codes += [barcode(d["barcode"]) for d in f["doors"] if d.get("barcode")]
            button = None
            if f.get("lobby"):
                lobby = f["lobby"]
                bx, by = lobby["button"]
                button = (float(bx), float(by), float(lobby["facing"]))
                codes.append(Barcode(int(lobby["barcode"]), button[0], button[1], button[2]))
            office = None
            if f.get("office"):
                codes.append(barcode(f["office"]["barcode"]))
                office = tuple((float(p[0]), float(p[1])) for p in f["office"]["polygon"])
            floors.append(
                Floor(
                    level=int(f["level"]),
                    name=str(f.get("name", "")),
                    walls=tuple(seg(w) for w in f["walls"]),
                    obstacles=tuple(
                        tuple((float(p[0]), float(p[1])) for p in poly) for poly in f["obstacles"]
                    ),
                    doors=tuple(seg(d["seg"]) for d in f["doors"]),
                    barcodes=tuple(codes),
                    button=button,
                    office=office,
                )
            )
        e = j["elevator"]
        cars = tuple(
            Car(
                id=int(c["id"]),
                x0=float(c["x0"]),
                y0=float(c["y0"]),
                x1=float(c["x1"]),
                y1=float(c["y1"]),
                door=seg(c["door"]),
                walls=tuple(seg(w) for w in c["walls"]),
                panel=(float(c["panel"]["x"]), float(c["panel"]["y"]), float(c["panel"]["facing"])),
                barcode=int(c["barcode"]),
            )
            for c in e["cars"]
        )
        return Building(
            name=str(j["name"]),
            robot_radius=float(j["robot_radius"]),
            floors=tuple(floors),
            cars=cars,
            open_s=(float(e["open_s"][0]), float(e["open_s"][1])),
            mission=dict(j["mission"]),
            source=source,
        )

    def floor(self, level: int) -> Floor:
        """The floor of this level.

        Raises:
            KeyError: no floor has it.
        """
        for f in self.floors:
            if f.level == level:
                return f
        raise KeyError(f"the building {self.name!r} has no floor {level}")

    @property
    def start(self) -> tuple[int, float, float, float]:
        """Where the mission starts: ``(floor, x, y, theta)``."""
        s = self.mission["start"]
        return int(s["floor"]), float(s["x"]), float(s["y"]), float(s["theta"])

    def in_office(self, level: int, x: float, y: float) -> bool:
        """Whether a point of a floor is in the office (where the message is delivered)."""
        office = self.floor(level).office if any(f.level == level for f in self.floors) else None
        return office is not None and _in_polygon(office, x, y)

    def bounds(self, level: int, margin: float = 1.0) -> tuple[float, float, float, float]:
        """The box around a floor's walls and the shafts: ``(xmin, ymin, xmax, ymax)``."""
        xs: list[float] = []
        ys: list[float] = []
        for x0, y0, x1, y1 in self.segments(level):
            xs += [x0, x1]
            ys += [y0, y1]
        if not xs:
            return (-margin, -margin, margin, margin)
        return (min(xs) - margin, min(ys) - margin, max(xs) + margin, max(ys) + margin)

    def segments(self, level: int) -> list[Segment]:
        """Every fixed segment of a floor: its walls, its obstacles' edges, the shafts' walls."""
        f = self.floor(level)
        out = list(f.walls) + f.obstacle_edges()
        for c in self.cars:
            out.extend(c.walls)
        return out


def _in_polygon(polygon: tuple[tuple[float, float], ...], x: float, y: float) -> bool:
    """Whether a point is inside a polygon (even-odd rule)."""
    inside = False
    n = len(polygon)
    for i in range(n):
        (ax, ay), (bx, by) = polygon[i], polygon[(i + 1) % n]
        if (ay > y) != (by > y) and x < ax + (y - ay) * (bx - ax) / (by - ay):
            inside = not inside
    return inside


def _opt_float(v: Any) -> float | None:
    return None if v is None else float(v)


def wrap(angle: float) -> float:
    """An angle in [-pi, pi)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi
