"""The scene model: frozen dataclasses, one per TOML table, SI units throughout.

Every field is declared with :func:`~scenes.schema.spec`, which carries its
unit, bounds and documentation; the parser and the README's field reference are
both generated from these declarations, so they cannot drift apart.

Coordinates are right-handed world metres with +z up. Colours are linear RGB
triples. Angles in scene files are degrees.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np

from scenes.precision import precision_problems
from scenes.schema import spec

Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]
RGB = tuple[float, float, float]
Size2 = tuple[int, int]


def _dark(name: str, values: RGB) -> list[tuple[str, str]]:
    """A light that emits nothing: no caustic to compare, and the comparison's
    relative metrics are undefined on a black reference."""
    if any(v > 0 for v in values):
        return []
    return [(name, "is zero in every channel: the light emits nothing, so the scene "
             "forms no caustic and a comparison has no reference to measure against")]


def _parallel(a: Vec3, b: Vec3) -> bool:
    """True when two non-zero vectors are (anti)parallel to within 1e-6 rad."""
    na, nb = np.asarray(a, float), np.asarray(b, float)
    cross = np.linalg.norm(np.cross(na, nb))
    return bool(cross <= 1e-6 * np.linalg.norm(na) * np.linalg.norm(nb))


# --------------------------------------------------------------------------- lights


@dataclass(frozen=True)
class PointLight:
    """Isotropic point light."""

    kind: ClassVar[str] = "point"
    section: ClassVar[str] = "`[light]`"
    position: Vec3 = spec(doc="Light position.", unit="m")
    intensity: RGB = spec(doc="Radiant intensity per channel.", unit="W/sr", ge=0)

    def validate(self) -> list[tuple[str, str]]:
        return _dark("intensity", self.intensity)


@dataclass(frozen=True)
class SpotLight:
    """Spot light: a point light restricted to a cone around ``direction``."""

    kind: ClassVar[str] = "spot"
    section: ClassVar[str] = "`[light]`"
    position: Vec3 = spec(doc="Light position.", unit="m")
    direction: Vec3 = spec(doc="Cone axis (need not be normalised).", nonzero=True)
    intensity: RGB = spec(doc="Radiant intensity on the axis.", unit="W/sr", ge=0)
    cutoff_angle: float = spec(doc="Half-angle of the cone.", unit="deg", gt=0, lt=90)
    beam_width: float | None = spec(
        None,
        doc="Half-angle of full intensity; between it and the cutoff the intensity "
        "falls off linearly in the angle, to 0 at the cutoff (Mitsuba's spot emitter). "
        "Defaults to the cutoff (a hard edge).",
        unit="deg", gt=0, lt=90,
    )

    def validate(self) -> list[tuple[str, str]]:
        problems = _dark("intensity", self.intensity)
        if self.beam_width is not None and self.beam_width > self.cutoff_angle:
            problems.append(("beam_width", "must be <= cutoff_angle"))
        return problems


@dataclass(frozen=True)
class DirectionalLight:
    """Distant light (the sun): parallel rays travelling along ``direction``."""

    kind: ClassVar[str] = "directional"
    section: ClassVar[str] = "`[light]`"
    direction: Vec3 = spec(
        doc="Direction the light travels (from the light into the scene).", nonzero=True
    )
    irradiance: RGB = spec(
        doc="Irradiance on a surface perpendicular to the rays.", unit="W/m²", ge=0
    )

    def validate(self) -> list[tuple[str, str]]:
        return _dark("irradiance", self.irradiance)


@dataclass(frozen=True)
class AreaLight:
    """Rectangular Lambertian emitter, rendered by the caustics-mapping method as
    ``samples`` point lights (the paper's Section 3.1) and by Mitsuba as an area
    emitter of the same total power."""

    kind: ClassVar[str] = "area"
    section: ClassVar[str] = "`[light]`"
    center: Vec3 = spec(doc="Centre of the emitting rectangle.", unit="m")
    normal: Vec3 = spec(doc="Direction the emitting side faces.", nonzero=True)
    size: Vec2 = spec(doc="Width and height of the rectangle.", unit="m", gt=0)
    intensity: RGB = spec(
        doc="Radiant intensity of the whole emitter along its normal "
        "(radiance = intensity / area).", unit="W/sr", ge=0,
    )
    samples: int = spec(16, doc="Point lights sampled on the rectangle.", ge=1, le=1024)

    def validate(self) -> list[tuple[str, str]]:
        return _dark("intensity", self.intensity)


Light = PointLight | SpotLight | DirectionalLight | AreaLight

# ------------------------------------------------------------------------ materials


@dataclass(frozen=True)
class DiffuseMaterial:
    """Lambertian material."""

    kind: ClassVar[str] = "diffuse"
    section: ClassVar[str] = "material"
    albedo: RGB = spec(doc="Diffuse reflectance.", ge=0, le=1)


@dataclass(frozen=True)
class DielectricMaterial:
    """Smooth dielectric (glass, water). A per-channel IOR calls for dispersion."""

    kind: ClassVar[str] = "dielectric"
    section: ClassVar[str] = "material"
    ior: float | RGB = spec(
        doc="Index of refraction, one value or one per RGB channel.", ge=1, le=10
    )
    absorption: RGB = spec(
        (0.0, 0.0, 0.0),
        doc="Absorption coefficient K_a of Beer-Lambert attenuation exp(-K_a d) (paper Eq. 7).",
        unit="1/m", ge=0,
    )
    fresnel: bool = spec(
        False,
        doc="Weight transmission by the Fresnel factor; off means every photon "
        "takes the refracted branch with weight one, as the paper assumes.",
    )

    @property
    def iors(self) -> RGB:
        """IOR per channel."""
        if isinstance(self.ior, tuple):
            return self.ior
        return (self.ior, self.ior, self.ior)


@dataclass(frozen=True)
class ConductorMaterial:
    """Perfect mirror-like conductor with a constant specular reflectance."""

    kind: ClassVar[str] = "conductor"
    section: ClassVar[str] = "material"
    reflectance: RGB = spec(doc="Specular reflectance.", ge=0, le=1)
    fresnel: bool = spec(False, doc="Reserved: conductors use constant reflectance.")


Material = DiffuseMaterial | DielectricMaterial | ConductorMaterial

# ------------------------------------------------------------------------ transforms


@dataclass(frozen=True)
class Transform:
    """Scale, then rotate (about x, then y, then z), then translate."""

    section: ClassVar[str] = "transform"
    translate: Vec3 = spec((0.0, 0.0, 0.0), doc="Translation.", unit="m")
    rotate: Vec3 = spec(
        (0.0, 0.0, 0.0), doc="Rotation angles about the x, y and z axes.", unit="deg"
    )
    scale: float = spec(1.0, doc="Uniform scale factor.", gt=0)


# ------------------------------------------------------------------------ receivers


@dataclass(frozen=True)
class PlaneReceiver:
    """Rectangular Lambertian plane. Its (u, v) are metres along ``u_axis`` and
    ``normal × u_axis`` from the centre."""

    kind: ClassVar[str] = "plane"
    section: ClassVar[str] = "`[[receivers]]`"
    center: Vec3 = spec(doc="Centre of the rectangle.", unit="m")
    size: Vec2 = spec(doc="Extent along u and v.", unit="m", gt=0)
    albedo: RGB = spec(doc="Diffuse reflectance.", ge=0, le=1)
    normal: Vec3 = spec((0.0, 0.0, 1.0), doc="Front-side normal.", nonzero=True)
    u_axis: Vec3 = spec((1.0, 0.0, 0.0), doc="Direction of +u.", nonzero=True)

    def validate(self) -> list[tuple[str, str]]:
        if _parallel(self.normal, self.u_axis):
            return [("u_axis", "must not be parallel to normal")]
        return []


@dataclass(frozen=True)
class SinesHeight:
    """z = amplitude · sin(2π (d · (x, y)) / wavelength + phase)."""

    kind: ClassVar[str] = "sines"
    section: ClassVar[str] = "height"
    amplitude: float = spec(doc="Amplitude.", unit="m", ge=0)
    wavelength: float = spec(doc="Wavelength.", unit="m", gt=0)
    direction: Vec2 = spec((1.0, 0.0), doc="Direction of travel in (x, y).", nonzero=True)
    phase: float = spec(0.0, doc="Phase.", unit="rad")


@dataclass(frozen=True)
class StepHeight:
    """Terraces: z = step_height · floor(x / step_width); depth discontinuities."""

    kind: ClassVar[str] = "steps"
    section: ClassVar[str] = "height"
    step_height: float = spec(doc="Rise of each step.", unit="m")
    step_width: float = spec(doc="Run of each step along x.", unit="m", gt=0)


@dataclass(frozen=True)
class RuggedHeight:
    """Seeded multi-octave value noise (a rugged seabed, paper Fig. 5)."""

    kind: ClassVar[str] = "rugged"
    section: ClassVar[str] = "height"
    amplitude: float = spec(doc="Peak-to-mean amplitude.", unit="m", ge=0)
    feature_size: float = spec(doc="Size of the coarsest octave's features.", unit="m", gt=0)
    octaves: int = spec(4, doc="Number of octaves.", ge=1, le=8)
    seed: int = spec(0, doc="Noise seed.", ge=0)


@dataclass(frozen=True)
class FileHeight:
    """Heights from a 2-D ``.npy`` array of metres, spanning the receiver's size
    (row 0 at v = -size/2, column 0 at u = -size/2)."""

    kind: ClassVar[str] = "file"
    section: ClassVar[str] = "height"
    file: str = spec(doc="Path of the `.npy` height array.", path=True)


Height = SinesHeight | StepHeight | RuggedHeight | FileHeight


@dataclass(frozen=True)
class HeightfieldReceiver:
    """Lambertian heightfield z = center.z + h(x, y) over a rectangle; (u, v) are
    metres along x and y from the centre."""

    kind: ClassVar[str] = "heightfield"
    section: ClassVar[str] = "`[[receivers]]`"
    center: Vec3 = spec(doc="Centre of the base rectangle.", unit="m")
    size: Vec2 = spec(doc="Extent along x and y.", unit="m", gt=0)
    albedo: RGB = spec(doc="Diffuse reflectance.", ge=0, le=1)
    height: Height = spec(doc="Height function.")
    resolution: Size2 = spec((129, 129), doc="Vertices along x and y.", ge=2, le=4096)


@dataclass(frozen=True)
class MeshReceiver:
    """Lambertian triangle mesh (OBJ/PLY). (u, v) are the mesh's own texture
    coordinates if it has them, else metres of its x, y projection."""

    kind: ClassVar[str] = "mesh"
    section: ClassVar[str] = "`[[receivers]]`"
    file: str = spec(doc="Mesh file (OBJ or PLY).", path=True)
    albedo: RGB = spec(doc="Diffuse reflectance.", ge=0, le=1)
    transform: Transform = spec(Transform(), doc="Placement of the mesh.")


Receiver = PlaneReceiver | HeightfieldReceiver | MeshReceiver

# ------------------------------------------------------------------ caustic objects


@dataclass(frozen=True)
class SphereObject:
    """Sphere, tessellated as an icosphere (both renderers get the same triangles)."""

    kind: ClassVar[str] = "sphere"
    section: ClassVar[str] = "`[[objects]]`"
    center: Vec3 = spec(doc="Centre.", unit="m")
    radius: float = spec(doc="Radius.", unit="m", gt=0)
    material: Material = spec(doc="Material (normally dielectric or conductor).")
    subdivisions: int = spec(5, doc="Icosphere subdivision level.", ge=1, le=7)


@dataclass(frozen=True)
class MeshObject:
    """Triangle mesh from a file, or a built-in (``builtin:bunny``: the Stanford
    bunny shipped in the pymeshlab wheel). A dielectric mesh must be closed
    (watertight); an open one of another material is rendered as an open surface
    (no back-face culling; effect `open_mesh`)."""

    kind: ClassVar[str] = "mesh"
    section: ClassVar[str] = "`[[objects]]`"
    file: str = spec(doc="Mesh file (OBJ or PLY) or `builtin:bunny`.", path=True)
    material: Material = spec(doc="Material.")
    fit_size: float | None = spec(
        None,
        doc="If set, centre the mesh's bounding box at the origin and scale its largest "
        "extent to this size before the transform.", unit="m", gt=0,
    )
    transform: Transform = spec(Transform(), doc="Placement of the mesh.")


@dataclass(frozen=True)
class Wave:
    """A travelling sine wave on a water surface."""

    section: ClassVar[str] = "`waves`"
    amplitude: float = spec(doc="Amplitude.", unit="m", ge=0)
    wavelength: float = spec(doc="Wavelength.", unit="m", gt=0)
    direction: Vec2 = spec((1.0, 0.0), doc="Direction of travel in (x, y).", nonzero=True)
    phase: float = spec(0.0, doc="Phase at t = 0.", unit="rad")
    speed: float = spec(0.0, doc="Phase speed.", unit="m/s", ge=0)


@dataclass(frozen=True)
class Plop:
    """A drop falling into the water at ``start``: a ring ripple spreading at
    ``speed``, damped over time (the paper's Fig. 8 animation)."""

    section: ClassVar[str] = "`plops`"
    position: Vec2 = spec(doc="Impact point, relative to the surface centre.", unit="m")
    amplitude: float = spec(doc="Initial amplitude.", unit="m", ge=0)
    wavelength: float = spec(doc="Ripple wavelength.", unit="m", gt=0)
    speed: float = spec(0.5, doc="Speed of the spreading ring.", unit="m/s", ge=0)
    width: float = spec(0.3, doc="Width of the ripple packet.", unit="m", gt=0)
    damping: float = spec(0.5, doc="Amplitude decay rate.", unit="1/s", ge=0)
    start: float = spec(0.0, doc="Time of impact.", unit="s")


@dataclass(frozen=True)
class WaterSurface:
    """Open water surface (one refraction): a heightfield grid of waves and plops."""

    kind: ClassVar[str] = "water_surface"
    section: ClassVar[str] = "`[[objects]]`"
    center: Vec3 = spec(doc="Centre of the still surface.", unit="m")
    size: Vec2 = spec(doc="Extent along x and y.", unit="m", gt=0)
    material: Material = spec(doc="Material (dielectric, IOR 1.33 for water).")
    resolution: Size2 = spec(
        (100, 100), doc="Vertices along x and y (the paper used 100×100).", ge=2, le=4096
    )
    waves: tuple[Wave, ...] = spec((), doc="Travelling sine waves.")
    plops: tuple[Plop, ...] = spec((), doc="Drop ripples.")
    time: float = spec(0.0, doc="Time at which the surface is evaluated.", unit="s")


@dataclass(frozen=True)
class RingObject:
    """Open cylindrical band (a metal ring, paper Fig. 12), two-sided."""

    kind: ClassVar[str] = "ring"
    section: ClassVar[str] = "`[[objects]]`"
    center: Vec3 = spec(doc="Centre of the band's base circle.", unit="m")
    radius: float = spec(doc="Radius.", unit="m", gt=0)
    height: float = spec(doc="Height of the band along the axis.", unit="m", gt=0)
    material: Material = spec(doc="Material (normally conductor).")
    axis: Vec3 = spec((0.0, 0.0, 1.0), doc="Axis of the band.", nonzero=True)
    segments: int = spec(256, doc="Facets around the band.", ge=8, le=8192)


CausticObject = SphereObject | MeshObject | WaterSurface | RingObject

# ------------------------------------------------------------------- camera, settings


@dataclass(frozen=True)
class Camera:
    """Pinhole camera."""

    section: ClassVar[str] = "`[camera]`"
    position: Vec3 = spec(doc="Eye position.", unit="m")
    look_at: Vec3 = spec(doc="Point looked at.", unit="m")
    fov: float = spec(doc="Field of view along `fov_axis`.", unit="deg", gt=0, lt=180)
    resolution: Size2 = spec(doc="Image width and height.", unit="px", ge=1, le=8192)
    up: Vec3 = spec((0.0, 0.0, 1.0), doc="Up vector.", nonzero=True)
    fov_axis: Literal["x", "y"] = spec("x", doc="Image axis the field of view spans.")

    def validate(self) -> list[tuple[str, str]]:
        eye, target = np.asarray(self.position), np.asarray(self.look_at)
        if np.linalg.norm(target - eye) == 0:
            return [("look_at", "must differ from position")]
        if _parallel(tuple(target - eye), self.up):
            return [("up", "must not be parallel to the viewing direction")]
        return []


@dataclass(frozen=True)
class Settings:
    """Renderer settings; each may be set per scene and overridden on the command
    line (``--set name=value``)."""

    section: ClassVar[str] = "`[settings]`"

    # caustics mapping
    grid: int = spec(128, doc="Refractive vertex grid resolution (grid × grid).", ge=2, le=4096)
    caustic_map: int = spec(512, doc="Caustic-map resolution per face.", unit="px", ge=8, le=8192)
    positions_map: int = spec(
        512, doc="Receiver positions-texture resolution per face.", unit="px", ge=8, le=8192
    )
    shadow_map: int = spec(1024, doc="Shadow-map resolution per face.", unit="px", ge=8, le=8192)
    preset: Literal["paper", "strong"] = spec(
        "paper", doc="Caustics-mapping preset: `paper` (the paper's choices, as published) "
        "or `strong` (the best known implementation). Settings left unset (`None`) take "
        "the preset's value; a setting given in the scene or on the command line wins.",
    )
    estimator: Literal["modified", "newton", "secant"] | None = spec(
        None, doc="Intersection estimator (preset: paper modified, strong secant)."
    )
    safeguarded: bool | None = spec(
        None, doc="Detect oscillation and fall back to a bracket (its false position, "
        "else its bisection); stop at a converged estimate (preset: paper false, "
        "strong true)."
    )
    iterations: int | None = spec(
        None, doc="Estimator iterations (preset: paper 3, strong 5).", ge=0, le=64
    )
    start: Literal["receiver", "fixed"] = spec(
        "receiver", doc="Start estimate: the receiver seen along the light ray through the "
        "vertex (d0 = 0, d1 = g(0); the paper's text), or `start_distance` (the appendix "
        "listing's Newton start).",
    )
    start_distance: float = spec(
        0.10, doc="Start distance of `start = \"fixed\"` (the listing's 0.10).", unit="m", gt=0
    )
    newton_eps: float | None = spec(
        None,
        doc="Finite-difference step of the Newton estimator; default 1e-3 of the "
        "light-to-receiver distance.", unit="m", gt=0,
    )
    lookup: Literal["nearest", "filtered"] | None = spec(
        None, doc="Surface texture reads (receiver positions, object front and back): "
        "nearest texel, or bilinear within one surface with renormalised normals "
        "(preset: paper nearest, strong filtered).",
    )
    back_resolution: int | None = spec(
        None, doc="Back-surface (exit) texture resolution per object view "
        "(preset: paper = grid, strong = 4 x grid, 2 x grid where every closed dielectric "
        "is convex).", unit="px", ge=2, le=8192,
    )
    rim_patches: int | None = spec(
        None, doc="Rim patches: each grid quad within one grid step of an object's "
        "silhouette seen from the light is traced again as a patch of n x n quads (n "
        "odd; 1: none), whose splats replace the quad's; they follow the strongly "
        "curved refraction and reflection at grazing light (preset: paper 1, strong 3, "
        "5 where the scene has a conductor).", ge=1, le=9,
    )
    frustum: Literal["square", "tight"] | None = spec(
        None, doc="Object view of the vertex grid: a square frustum around the objects' "
        "bounding sphere, or a rectangular, asymmetric one fitted to their projection "
        "(preset: paper square, strong tight).",
    )
    verify_hits: bool | None = spec(
        None, doc="Accept an estimate only if its residual |T(P) - P| is within "
        "`hit_tolerance` and a receiver is seen at P; else the vertex is `unconverged` "
        "(preset: paper false, strong true).",
    )
    hit_tolerance: float | None = spec(
        None, doc="Residual a verified hit may have; default one positions-map texel at "
        "the hit's distance, over the cosine between light ray and receiver normal "
        "(at most 10).", unit="m", gt=0,
    )
    splat_unconverged: bool = spec(
        False, doc="Splat `unconverged` vertices anyway (they are counted either way)."
    )
    splat: Literal["points", "footprint", "triangles"] | None = spec(
        None, doc="Splat kernel: `points` (the paper's Gaussian of one width), `footprint` "
        "(a Gaussian per vertex shaped by its neighbours' hits) or `triangles` (the grid's "
        "quads between neighbouring hits, irradiance = flux / area). All conserve each "
        "vertex's flux (preset: paper points, strong triangles).",
    )
    splat_sigma: float | None = spec(
        None,
        doc="Standard deviation of the `points` Gaussian. Default: paper preset "
        "0.5 x caustic_map / grid (half a grid cell of a grid spanning the caustic map's "
        "view; about two grid cells under a fitted object frustum); otherwise one mean "
        "spacing of neighbouring hits on the receiver.", unit="caustic-map texels", gt=0,
    )
    footprint_scale: float = spec(
        0.5, doc="`footprint` splats: the Gaussian's covariance is this squared times the "
        "outer products of the grid's hit differences (0.5: half the local spacing).", gt=0,
    )
    splat_radius: float = spec(
        3.0, doc="Splat cut-off radius, in standard deviations.", gt=0, le=8
    )
    normalization: Literal["radiometric", "paper"] = spec(
        "radiometric", doc="Flux per grid texel: physical, or the paper's Eq. 6."
    )
    lowpass: bool = spec(False, doc="Low-pass filter the caustic map the camera reads.")
    caustic_lookup: Literal["light", "receivers"] | None = spec(
        None, doc="Where the camera reads caustic irradiance: the light-space caustic map "
        "(the paper's), or the receivers' own (u, v) maps, whose triangles are drawn for "
        "it at 2 x `receiver_map` (their 2 x 2 means enter the scored maps); the "
        "light-space map is then drawn only for the `render` command's outputs "
        "(preset: paper light, strong receivers).",
    )
    receiver_map: Size2 = spec(
        (256, 256), doc="Receiver irradiance map resolution over (u, v).", unit="px",
        ge=2, le=8192,
    )
    # Mitsuba reference
    photons: int = spec(
        2_097_152, doc="Starting photon budget of the reference photon tracer per seed, "
        "traced in launches of 2^20 photons (the default is two whole launches; a "
        "remainder is one smaller launch). Past it the reference traces more launches "
        "while its noise is above `target_noise` and the target is in reach within "
        "`reference_time_cap`.", ge=1,
    )
    spp: int = spec(16, doc="Reference camera samples per pixel per seed (camera tracer: "
                     "stratified subpixel samples, 4 x 4 by default; ptracer: particles per "
                     "pixel).", ge=1)
    seed: int = spec(0, doc="First random seed.", ge=0)
    seeds: int = spec(4, doc="Independent seeds K for the reference's variance.", ge=1, le=64)
    target_noise: float = spec(
        0.01, doc="Stop when the reference's relative noise in the caustic region "
        "is below this: the RMS relative standard error of each RGB channel over the "
        "reference's own caustic region, the largest channel's.", gt=0,
    )
    reference_time_cap: float = spec(
        120.0, doc="Time cap of the reference's receiver maps (all seeds, wall clock "
        "from their start): launches past the starting `photons` budget are traced only "
        "while `target_noise` looks reachable within it, and never after it.",
        unit="s", gt=0,
    )
    all_specular_paths: bool = spec(
        False, doc="Count every L S+ D path, not only the chains the effects name."
    )

    def validate(self) -> list[tuple[str, str]]:
        if self.rim_patches is not None and self.rim_patches % 2 == 0:
            return [("rim_patches", "must be odd (a patch's vertices include its quad's "
                     "corners at the finer grid's texel centres)")]
        if (self.rim_patches or 1) > 1 and self.normalization == "paper":
            return [("rim_patches", "needs normalization = \"radiometric\" (the paper's "
                     "Eq. 6 counts the grid's own texels)")]
        splat = self.splat or ("points" if self.preset == "paper" else "triangles")
        if (self.rim_patches or 1) > 1 and splat != "triangles":
            return [("rim_patches", f"needs splat = \"triangles\" (not {splat!r}): a patch "
                     "replaces its quad's triangles")]
        return []


@dataclass(frozen=True)
class SceneInfo:
    """Name, description and scene-wide switches."""

    section: ClassVar[str] = "`[scene]`"
    name: str = spec(doc="Scene name (used for output folders).")
    description: str = spec("", doc="What the scene shows and which paper figure it mirrors.")
    direct_lighting: bool = spec(
        True,
        doc="Receivers are also lit directly by the light. Off when every light path "
        "to the receivers passes the caustic object (a pool under a water surface).",
    )
    shadows: bool = spec(
        True, doc="Caustic objects occlude direct light (runs the shadow-map pass)."
    )

    def validate(self) -> list[tuple[str, str]]:
        if not self.name.strip():
            return [("name", "must not be empty")]
        return []


# ------------------------------------------------------------------------- animation


_ZERO3: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class LightMotion:
    """Motion of the light over the animation, as a function of the time τ (s)
    since the scene as written (``scenes.animation``)."""

    section: ClassVar[str] = "`[animation.light]`"
    velocity: Vec3 = spec(
        _ZERO3, doc="Velocity of the light's position (point, spot) or centre (area): "
        "p(τ) = p + v τ. A directional light has no position: must be zero.", unit="m/s",
    )
    angular_velocity: Vec3 = spec(
        _ZERO3, doc="Rate of the rotation angles of the light's direction (spot, "
        "directional) or normal (area): the direction is rotated by the angles ω τ about x, "
        "then y, then z (as `transform.rotate`). A point light has no direction: must be "
        "zero.", unit="deg/s",
    )


@dataclass(frozen=True)
class ObjectMotion:
    """Motion of one caustic object over the animation."""

    section: ClassVar[str] = "`[[animation.objects]]`"
    index: int = spec(doc="The object that moves: its index in `[[objects]]` (0 = first).",
                      ge=0)
    velocity: Vec3 = spec(
        _ZERO3, doc="Translation rate: the centre (sphere, water surface, ring) or the "
        "transform's `translate` (mesh) moves by v τ.", unit="m/s",
    )
    angular_velocity: Vec3 = spec(
        _ZERO3, doc="Rotation rate: a mesh's `transform.rotate` angles grow by ω τ (a spin "
        "about the mesh's own origin, its bounding-box centre with `fit_size`); a ring's "
        "axis is rotated by the angles ω τ about its centre. A sphere and a water surface "
        "have no orientation to turn: must be zero.", unit="deg/s",
    )


#: Object kinds that have no orientation an angular velocity could turn.
_UNROTATABLE = {"sphere": "a sphere has no orientation to turn (its tessellation is fixed)",
                "water_surface": "a water surface's grid stays aligned with x and y"}


@dataclass(frozen=True)
class Animation:
    """An animated scene: ``frames`` frames at ``fps``. Frame i is the scene at
    τ_i = start + i / fps seconds after the scene as written: every water surface at
    its ``time`` + τ_i (waves travel, plops spread), the light and the objects of
    ``objects`` moved by their velocities. ``caustics compare --studies temporal``
    renders the frames on both sides."""

    section: ClassVar[str] = "`[animation]`"
    frames: int = spec(24, doc="Frames in the sequence (`--frames` overrides it).",
                       ge=2, le=10_000)
    fps: float = spec(30.0, doc="Frames per second: frame i is at τ = start + i / fps.",
                      unit="1/s", gt=0, le=10_000)
    start: float = spec(0.0, doc="τ of the first frame, after the scene as written.",
                        unit="s")
    light: LightMotion = spec(LightMotion(), doc="Motion of the light.")
    objects: tuple[ObjectMotion, ...] = spec((), doc="Motions of caustic objects.")

    def validate(self) -> list[tuple[str, str]]:
        problems, seen = [], {}
        for k, motion in enumerate(self.objects):
            if motion.index in seen:
                problems.append((f"objects[{k}].index", f"object {motion.index} already "
                                 f"moves in animation.objects[{seen[motion.index]}]"))
            seen.setdefault(motion.index, k)
        return problems

    def scene_problems(self, scene: Scene) -> list[tuple[str, str]]:
        """(path under ``animation``, message) for motions the scene cannot take."""
        problems = []
        kind = type(scene.light).kind
        if kind == "directional" and any(self.light.velocity):
            problems.append(("light.velocity", "must be zero: a directional light has "
                             "no position to move (turn it with angular_velocity)"))
        if kind == "point" and any(self.light.angular_velocity):
            problems.append(("light.angular_velocity", "must be zero: a point light has "
                             "no direction to turn (move it with velocity)"))
        for k, motion in enumerate(self.objects):
            if motion.index >= len(scene.objects):
                problems.append((f"objects[{k}].index", f"must name an object: the scene "
                                 f"has {len(scene.objects)} (0 to {len(scene.objects) - 1})"))
                continue
            target = type(scene.objects[motion.index]).kind
            if any(motion.angular_velocity) and target in _UNROTATABLE:
                problems.append((f"objects[{k}].angular_velocity",
                                 f"must be zero: {_UNROTATABLE[target]}"))
        return problems


@dataclass(frozen=True)
class Scene:
    """A whole scene file."""

    section: ClassVar[str] = "scene file"
    info: SceneInfo = spec(doc="Name, description, switches.", key="scene")
    light: Light = spec(doc="The light source.")
    receivers: tuple[Receiver, ...] = spec(doc="Diffuse receivers of caustics.")
    objects: tuple[CausticObject, ...] = spec(doc="Caustic-forming objects.")
    camera: Camera = spec(doc="The camera.")
    settings: Settings = spec(Settings(), doc="Renderer settings.")
    animation: Animation | None = spec(
        None, doc="How the scene moves over a sequence of frames (the temporal study); "
        "none: a still scene (the temporal study then animates only its water surfaces' "
        "time).",
    )
    source: str = spec("", doc="Path of the file the scene was read from.", internal=True)

    def validate(self) -> list[tuple[str, str]]:
        problems = []
        if not self.receivers:
            problems.append(("receivers", "needs at least one receiver"))
        if not self.objects:
            problems.append(("objects", "needs at least one caustic object"))
        if self.animation is not None:
            problems += [(f"animation.{path}", message)
                         for path, message in self.animation.scene_problems(self)]
        return problems + precision_problems(self)

    @property
    def name(self) -> str:
        """The scene's name."""
        return self.info.name
