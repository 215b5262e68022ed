"""The particles of an lbm-server scene file, as the scene crate makes them (plain Python 3.11+).

A DEM that joins a run (``lbm-server run SCENE --dem external``) brings its own particles: the
protocol carries none. To run the scene's particles, a DEM builds them from the scene file; this
module reads them the way ``scene::Scene::initial_particles`` does, ids 0, 1, 2, ... in this order:

1. ``[[particles.sphere]]``, in file order;
2. ``[[particles.block]]``: a simple cubic lattice, x fastest, then y, then z;
3. ``[[dem.insert]]``: a lattice moved by a random offset of at most ``jitter`` per axis, radii
   uniform in ``radius = [min, max]``, from the SplitMix64 stream of ``seed`` (default 1): per
   sphere three draws for the offsets x, y, z, then one for the radius (bit for bit the scene's);
4. ``[[dem.csv]]``: rows of a CSV file (header naming x, y, z, r or radius; optional vx, vy, vz,
   wx, wy, wz; a relative path is taken next to the scene file, else from the working folder).

    import lbmdem_scene                # clients/python on PYTHONPATH, beside lbmdem/
    scene = lbmdem_scene.Scene.load("validation/scenes/ten-cate-e1.toml")
    for p in scene.particles:          # SceneParticle(id, position, velocity, angular_velocity,
        ...                            #               radius, material, density)

It reads; it does not validate (``lbm-server`` does, and refuses a bad scene with exit 2). A file
that cannot be read or is not TOML raises ``SceneError``. Every Python DEM client uses it: the YADE
module (clients/yade), the LIGGGHTS adapter (clients/liggghts, which checks its deck's atom count
against ``len(scene.particles)``) and the YADE script / LIGGGHTS deck that ``lbm-server run SCENE
--dem yade|liggghts`` writes.
"""

from __future__ import annotations

import os
import tomllib
from typing import NamedTuple, Optional

__all__ = ["SceneParticle", "Material", "Scene", "SceneError", "SplitMix64"]

#: The scene crate's defaults of a `[[dem.material]]` (scene/src/dem.rs).
DEFAULT_MATERIAL = {"name": "default", "young_modulus": 5.0e6, "poisson_ratio": 0.3,
                    "restitution": 0.9, "friction": 0.5, "rolling_friction": 0.0}
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)
_MASK = (1 << 64) - 1


class SceneError(ValueError):
    """The scene file cannot be read."""


class SplitMix64:
    """The scene crate's random source for jitter and radii (SplitMix64)."""

    def __init__(self, seed: int):
        self.state = seed & _MASK

    def next(self) -> int:
        self.state = (self.state + 0x9E3779B97F4A7C15) & _MASK
        z = self.state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK
        return z ^ (z >> 31)

    def unit(self) -> float:
        """Uniform in [0, 1)."""
        return (self.next() >> 11) / float(1 << 53)


class Material(NamedTuple):
    name: str
    young_modulus: float
    poisson_ratio: float
    restitution: float
    friction: float
    rolling_friction: float
    density: float


class SceneParticle(NamedTuple):
    """One particle of the scene: its id on the wire, initial state [SI] and material."""

    id: int
    position: tuple
    velocity: tuple
    angular_velocity: tuple
    radius: float
    material: str
    density: float


class Scene:
    """What a DEM needs of a scene file: particles, materials, gravity, domain, the coupling."""

    def __init__(self, data: dict, path: str = "<scene>"):
        self.path = path
        self.data = data
        self.name = data.get("name", "")
        self.gravity = tuple(float(g) for g in data.get("gravity", DEFAULT_GRAVITY))
        domain = data.get("domain", {})
        self.domain_min = tuple(domain.get("min", (0.0, 0.0, 0.0)))
        self.domain_max = tuple(domain.get("max", (0.0, 0.0, 0.0)))
        self.coupling = data.get("coupling", {})
        self.lattice = data.get("lattice")
        dem = data.get("dem", {})
        self.density = float(data.get("particles", {}).get("density", float("nan")))
        self.materials = {m.name: m for m in (self._material(m) for m in dem.get("material", []))}
        if not self.materials:
            self.materials = {"default": self._material(DEFAULT_MATERIAL)}
        self.particle_material = dem.get("particle_material") or next(iter(self.materials))
        self.particles = self._particles()

    @classmethod
    def load(cls, path: str) -> "Scene":
        try:
            with open(path, "rb") as f:
                data = tomllib.load(f)
        except (OSError, tomllib.TOMLDecodeError) as e:
            raise SceneError(f"{path}: {e}") from None
        return cls(data, str(path))

    @property
    def capacity(self) -> int:
        """Most particles a step may carry (`coupling.capacity`, default the particle count)."""
        return max(int(self.coupling.get("capacity", len(self.particles))), 1)

    @property
    def lubrication(self) -> bool:
        """Whether the run has the squeeze-film correction below one cell (`coupling.lubrication`
        with a `[lattice]`)."""
        return bool(self.coupling.get("lubrication", True)) and self.lattice is not None

    def cell_size(self) -> float:
        """The lattice's cell size dx [m] (`lattice.dx`, or the domain's x length over
        `lattice.resolution`): the squeeze films' cut-off (PROTOCOL.md 4.5)."""
        lattice = self.lattice or {}
        if "dx" in lattice:
            return float(lattice["dx"])
        if "resolution" in lattice:
            return (self.domain_max[0] - self.domain_min[0]) / float(lattice["resolution"])
        raise SceneError(f"{self.path}: the scene has no lattice.dx or lattice.resolution")

    def _material(self, m: dict) -> Material:
        full = {**DEFAULT_MATERIAL, **m}
        density = full.get("density", self.density)
        return Material(full["name"], float(full["young_modulus"]), float(full["poisson_ratio"]),
                        float(full["restitution"]), float(full["friction"]),
                        float(full["rolling_friction"]), float(density))

    def material(self, name: Optional[str]) -> Material:
        return self.materials[name or self.particle_material]

    def _particles(self) -> list:
        p = self.data.get("particles", {})
        zero = (0.0, 0.0, 0.0)
        own = self.particle_material
        rows = [(tuple(s["position"]), tuple(s.get("velocity", zero)),
                 tuple(s.get("angular_velocity", zero)), float(s["radius"]), own)
                for s in p.get("sphere", [])]
        for b in p.get("block", []):
            rows += [(c, tuple(b.get("velocity", zero)), zero, float(b["radius"]), own)
                     for c in _lattice_centres(b["origin"], b["count"], b["spacing"])]
        dem = self.data.get("dem", {})
        for ins in dem.get("insert", []):
            rows += _jittered_lattice(ins, ins.get("material") or own)
        for csv in dem.get("csv", []):
            rows += _csv_rows(self._beside(csv["file"]), csv.get("material") or own)
        return [SceneParticle(i, pos, vel, spin, r, mat, self.material(mat).density)
                for i, (pos, vel, spin, r, mat) in enumerate(rows)]

    def _beside(self, file: str) -> str:
        if os.path.isabs(file):
            return file
        beside = os.path.join(os.path.dirname(self.path), file)
        return beside if os.path.isfile(beside) else file


def _lattice_centres(origin, count, spacing):
    nx, ny, nz = (int(c) for c in count)
    return [tuple(origin[a] + ijk[a] * spacing for a in range(3))
            for ijk in ((i, j, k) for k in range(nz) for j in range(ny) for i in range(nx))]


def _jittered_lattice(ins: dict, material: str) -> list:
    """scene/src/dem.rs `lattice`: per sphere three offsets, then the radius, from one stream."""
    rng = SplitMix64(int(ins.get("seed", 1)))
    radius = ins["radius"]
    lo, hi = (radius, radius) if isinstance(radius, (int, float)) else radius
    jitter = float(ins.get("jitter", 0.0))
    velocity = tuple(ins.get("velocity", (0.0, 0.0, 0.0)))
    nx, ny, nz = (int(c) for c in ins["count"])
    out = []
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                ijk = (i, j, k)
                pos = tuple(ins["origin"][a] + ijk[a] * ins["spacing"]
                            + jitter * (2.0 * rng.unit() - 1.0) for a in range(3))
                r = lo + (hi - lo) * rng.unit()
                out.append((pos, velocity, (0.0, 0.0, 0.0), r, material))
    return out


def _csv_rows(path: str, material: str) -> list:
    with open(path) as f:
        lines = [l for l in f.read().splitlines() if l.strip() and not l.startswith("#")]
    header = [c.strip().lower() for c in lines[0].split(",")]

    def col(*names):
        return next((header.index(n) for n in names if n in header), None)

    x, y, z, r = col("x"), col("y"), col("z"), col("r", "radius")
    optional = [col(n) for n in ("vx", "vy", "vz", "wx", "wy", "wz")]
    out = []
    for line in lines[1:]:
        cells = [c.strip() for c in line.split(",")]
        num = (lambda c: 0.0 if c is None else float(cells[c]))
        out.append(((num(x), num(y), num(z)), tuple(num(c) for c in optional[:3]),
                    tuple(num(c) for c in optional[3:]), num(r), material))
    return out
