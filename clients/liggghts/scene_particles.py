"""How many particles a scene file creates, so that a deck's atoms can be checked against it.

The scene (``scene/src/lib.rs``, ``Scene::initial_particles``) numbers its particles 0, 1, 2, ...:
``particles.sphere`` first, then each ``particles.block`` (count x * y * z), then each
``dem.insert`` (count x * y * z) and each ``dem.csv`` (one per data row). Only the count is read
here; positions and radii are the deck's.
"""

from __future__ import annotations

import math
import os

try:
    import tomllib
except ImportError:  # Python < 3.11
    try:
        import tomli as tomllib  # type: ignore[no-redef]
    except ImportError:
        tomllib = None  # type: ignore[assignment]


class SceneError(Exception):
    """The scene file cannot be read."""


def _csv_rows(scene_path: str, path: str) -> int:
    """Data rows of a ``dem.csv`` file: lines but blank ones, '#' comments and the header."""
    beside = os.path.join(os.path.dirname(scene_path), path)
    resolved = path if os.path.isabs(path) or not os.path.isfile(beside) else beside
    try:
        with open(resolved, encoding="utf-8") as f:
            lines = [l for l in f if l.strip() and not l.startswith("#")]
    except OSError as e:
        raise SceneError(f"{scene_path}: dem.csv file {path!r}: {e}") from None
    return max(len(lines) - 1, 0)


def particle_count(scene_path: str) -> int:
    """The number of particles ``scene_path`` creates (their ids are 0 .. count - 1)."""
    if tomllib is None:
        raise SceneError("reading the scene needs Python 3.11 (tomllib) or the tomli package")
    try:
        with open(scene_path, "rb") as f:
            scene = tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise SceneError(f"{scene_path}: {e}") from None
    particles, dem = scene.get("particles", {}), scene.get("dem", {})
    count = len(particles.get("sphere", []))
    count += sum(math.prod(b.get("count", [0])) for b in particles.get("block", []))
    count += sum(math.prod(i.get("count", [0])) for i in dem.get("insert", []))
    count += sum(_csv_rows(scene_path, c.get("file", "")) for c in dem.get("csv", []))
    return count
