"""Offscreen movies and stills of a trajectory with pyvista: ``hsgran render`` (layer 6).

:func:`render` reads an HDF5 trajectory and writes an MP4 or GIF movie, a folder of PNG frames
or one PNG still, without a display: VTK draws into an EGL surface (Mesa's software rasteriser
on a machine without GPU). What each frame shows (times, interpolated positions, spin, colours,
camera, walls) comes from :mod:`hsgran.animation`; this module draws it and writes the files.

* Spheres are drawn at their true radii: up to :data:`MESH_SPHERES_MAX` spheres as meshes with a
  body-fixed two-tone octant pattern (a beach ball) that turns with the sphere, above that as
  shaded impostors (one camera-facing quad each, :data:`SPHERE_SHADER`) with two antipodal
  body-fixed marker dots. Either way a rolling sphere's pattern turns as it advances and a
  sliding one's does not.
* Plane walls are finite rectangles with a checker texture (a reference to see motion against),
  drawn from the spheres' side only, so the near walls of a box hide nothing.
* Output is written to a temporary file beside the target and renamed at the end: an
  interrupted or failed render never leaves a half-written movie under the target's name.

VTK segfaults instead of raising when the system GL libraries are missing
(docs/architecture.md §6), so :func:`missing_system_libraries` checks for them before anything
creates a render window, and ``VTK_DEFAULT_OPENGL_WINDOW`` is set to the EGL window before
pyvista is imported.
"""

from __future__ import annotations

import contextlib
import ctypes
import glob
import math
import os
import shutil
import sys
import tempfile
import time as _time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hsgran.animation import (
    MARKER_AXIS,
    Camera,
    CameraSpec,
    FrameState,
    Playback,
    camera_at,
    check_camera,
    check_color_by,
    nice_spacing,
    nice_step_above,
    parse_camera,
    part_surfaces,
    resolve_camera,
    sample_times,
    scene_extent,
    time_label_decimals,
    wall_patches,
)
from hsgran.errors import InputError, MissingDependency
from hsgran.io.h5md import read_trajectory
from hsgran.scene import Cylinder, Plane, parse_scene
from hsgran.wallspec import (
    BL_RADIUS,
    CY_AXIS,
    CY_HALF,
    CY_OMEGA,
    CY_RADIUS,
    CY_SIDE,
    M_KIND,
    MOT_FIXED,
    WK_BALL,
)

# ---- environment -------------------------------------------------------------------------

#: Environment variable that picks VTK's render window class, and the offscreen class we use.
WINDOW_VARIABLE = "VTK_DEFAULT_OPENGL_WINDOW"
EGL_WINDOW = "vtkEGLRenderWindow"
#: Debian packages that provide libEGL and Mesa's software rasteriser (docs/architecture.md §6).
GL_PACKAGES = "libegl1 libgl1-mesa-dri"
#: Set to 1 to skip the library check (a GL stack our search does not know about).
SKIP_CHECK_VARIABLE = "HSGRAN_SKIP_GL_CHECK"
#: The pip extra that brings pyvista, vtk, imageio, imageio-ffmpeg and matplotlib.
RENDER_EXTRA = "pip install -e '.[render]'"

# ---- defaults and limits -----------------------------------------------------------------

DEFAULT_SIZE = (1280, 720)
DEFAULT_FPS = 30.0
#: H.264 in yuv420p works on 16×16 macroblocks: MP4 frames are rounded up to multiples of 16
#: (rather than rescaled by the encoder, which would blur them).
MP4_BLOCK = 16
#: Smallest and largest picture edge [px]: below 16 nothing is recognisable; 8192 is where
#: Mesa's software rasteriser and most video players give up.
MIN_EDGE, MAX_EDGE = 16, 8192
#: imageio-ffmpeg's quality scale (0-10); 8 keeps the checker floor free of visible blocking at
#: about 1 MB per 10 s of 1280×720.
MP4_QUALITY = 8
#: Output kinds by file extension.
MOVIE_SUFFIXES = {".mp4": "mp4", ".gif": "gif"}
STILL_SUFFIXES = {".png": "png"}
#: Names of the PNG frames written by ``--frames DIR`` (frame number, zero-padded).
FRAME_PATTERN = "frame_{:05d}.png"

# ---- look --------------------------------------------------------------------------------

#: Up to this many spheres are drawn as meshes with the octant pattern; more are drawn as
#: impostors, whose cost does not grow with their size on screen.
MESH_SPHERES_MAX = 50
#: Sphere meshes get one segment around per this many pixels of the (largest) sphere's
#: circumference on screen, within [MIN, MAX] segments: Mesa's software rasteriser spends
#: ~0.7 µs per triangle, so 10 spheres at a fixed 48 segments cost 20 ms per frame, while a
#: polygon edge of 6 px still reads as round.
SEGMENT_PIXELS = 6.0
MIN_SEGMENTS, MAX_SEGMENTS = 12, 64
#: Most triangles of all sphere meshes together (~15 ms per frame): many large spheres get
#: fewer segments than their size asks for. A mesh of s segments has about 4/3 s² triangles.
TRIANGLE_BUDGET = 20_000
#: Brightness of the dark octants relative to the sphere's colour [-]: dark enough to see the
#: turn, light enough that the colour still reads.
PATTERN_SHADE = 0.45
#: Impostor spin markers: centre at this fraction of the radius from the sphere's centre along
#: ± the body-fixed marker axis, radius this fraction of the sphere's. 0.75 + 0.25 = 1 keeps a
#: marker inside the sphere's outline when it sits on the rim.
MARKER_OFFSET = 0.75
MARKER_RADIUS = 0.25
#: A marker is dark on a light sphere and light on a dark one (Rec. 709 luma threshold [-]).
MARKER_LUMA_SPLIT = 0.5
MARKER_DARK, MARKER_LIGHT = (25, 25, 30), (245, 245, 245)
#: Background, sRGB [0-1]: light, so that dark markers and text read. Plain: a gradient costs
#: ~10 ms per 1280×720 frame in Mesa's software rasteriser.
BACKGROUND = (0.90, 0.92, 0.95)
#: Checker squares of the walls (two light greys, sRGB 0-255). Walls are opaque: they are drawn
#: from the spheres' side only (backface culling), and a sphere can never be behind a wall seen
#: from that side, so transparency would show nothing more and cost a blending pass.
CHECKER_COLORS = ((222, 222, 226), (196, 198, 204))
#: Texture of one checker period (2 × 2 squares) [px]: large enough that linear filtering only
#: softens the squares' edges.
CHECKER_TEXELS = 64
#: Facets around a cylinder wall, and the stripes along it (an even number; they show a drum
#: turn).
CYLINDER_SEGMENTS = 96
#: Segments around a fixed sphere's mesh (half as many from pole to pole): smooth at the
#: sizes a bed of fixed spheres is seen at, and a bed of thousands stays a few hundred
#: thousand triangles.
FIXED_SPHERE_SEGMENTS = 16
CYLINDER_STRIPES = 24
#: Walls are shaded by a light fixed in the world, from above, front and right (a direction,
#: normalised at use), with this share of ambient light [-]: a floor is brightest and the walls
#: of a box differ from each other.
WALL_LIGHT = (0.35, -0.55, 1.0)
WALL_AMBIENT = 0.72
#: Box edges: colour (sRGB) and width [px].
EDGE_COLOR, EDGE_WIDTH = (0.35, 0.37, 0.42), 1.5
#: Text height: picture height / this [px]; never below MIN_FONT px, the smallest still legible.
TEXT_SCALE = 36
MIN_FONT = 8
#: Opacity of the legend's white panel [-]: the scene stays faintly visible behind it.
LEGEND_OPACITY = 0.75
#: Colour map of ``--color-by speed`` (perceptually uniform, readable on the light background).
SPEED_CMAP = "viridis"
#: At most this many intervals between the colour bar's labels.
SPEED_TICKS = 5
#: Shading of the impostors (GLSL, replaces the colour part of VTK's point-Gaussian fragment
#: shader). offsetVCVSOutput is the fragment's offset from the sphere's centre in units of its
#: radius, in the splat's own 2-D frame, which VTK 9.7 turns differently for every splat; its
#: screen derivatives give the map back to screen axes, so the normal of the sphere's front
#: surface (and with it the light, fixed to the camera above left in front, as VTK's headlight
#: is) is the same for every sphere. Outside the unit disk is discarded; inside, a Lambert term
#: and a Phong highlight.
SPHERE_SHADER = """//VTK::Color::Impl
vec2 offset = offsetVCVSOutput.xy;
float r2 = dot(offset, offset);
if (r2 > 1.0) { discard; }
mat2 toScreen = inverse(mat2(dFdx(offset), dFdy(offset)));
vec2 across = toScreen * offset / length(toScreen * vec2(1.0, 0.0));
vec3 nrm = vec3(across, sqrt(1.0 - r2));
vec3 light = normalize(vec3(-0.35, 0.55, 1.0));
float lambert = max(dot(nrm, light), 0.0);
float highlight = pow(max(dot(reflect(-light, nrm), vec3(0.0, 0.0, 1.0)), 0.0), 40.0);
diffuseColor = diffuseColor * (0.3 + 0.7 * lambert) + vec3(0.35 * highlight);
ambientColor = vec3(0.0);
"""


# ---- environment checks --------------------------------------------------------------------

def missing_system_libraries() -> str | None:
    """What to install for offscreen rendering, or ``None`` when nothing is missing.

    Checks that libEGL loads and, when Mesa provides EGL (the case without a vendor driver),
    that a Mesa software DRI driver exists. Skipped when ``VTK_DEFAULT_OPENGL_WINDOW`` names
    another window class or ``HSGRAN_SKIP_GL_CHECK=1``.

    Returns:
        A one-line instruction, or ``None``.
    """
    if os.environ.get(SKIP_CHECK_VARIABLE) == "1":
        return None
    if os.environ.get(WINDOW_VARIABLE, EGL_WINDOW) not in (EGL_WINDOW, ""):
        return None
    instruction = (f"offscreen rendering needs the system libraries {GL_PACKAGES}: as root, "
                   f"run 'apt-get install -y --no-install-recommends {GL_PACKAGES}' (or "
                   "'bash tools/setup.sh')")
    try:
        ctypes.CDLL("libEGL.so.1")
    except OSError:
        return instruction
    vendors = glob.glob("/usr/share/glvnd/egl_vendor.d/*.json") + glob.glob(
        "/etc/glvnd/egl_vendor.d/*.json")
    if vendors and not any("mesa" in Path(v).name for v in vendors):
        return None                    # a vendor driver (NVIDIA, ...) renders without Mesa
    if not vendors:
        return instruction             # libEGL without any implementation behind it
    dirs = [d for d in os.environ.get("LIBGL_DRIVERS_PATH", "").split(":") if d]
    dirs += [*glob.glob("/usr/lib/*/dri"), "/usr/lib/dri", "/usr/lib64/dri"]
    if any(glob.glob(os.path.join(d, "*swrast_dri.so")) for d in dirs):
        return None
    return instruction


def _import_pyvista():
    """pyvista with VTK's offscreen EGL window selected, or MissingDependency."""
    if not os.environ.get(WINDOW_VARIABLE):
        # an empty value would make VTK pick an on-screen window and fail without a display
        os.environ[WINDOW_VARIABLE] = EGL_WINDOW
    try:
        import imageio  # noqa: F401
        import matplotlib  # noqa: F401
        import pyvista
    except ImportError as exc:
        raise MissingDependency(f"rendering needs the 'render' extra ({exc.name} is missing): "
                                f"{RENDER_EXTRA}") from None
    return pyvista


# ---- options -----------------------------------------------------------------------------

@dataclass(frozen=True)
class RenderResult:
    """What :func:`render` wrote.

    Attributes:
        output: The movie, still or frame folder written.
        kind: ``mp4``, ``gif``, ``frames`` or ``png``.
        frames: Number of frames.
        size: Width and height of the frames [px].
        fps: Frames per second of video [1/s].
        time_scale: Simulated seconds per second of video [-].
        seconds_per_frame: Wall time to draw one frame [s] (mean, writing excluded).
    """

    output: Path
    kind: str
    frames: int
    size: tuple[int, int]
    fps: float
    time_scale: float
    seconds_per_frame: float


def output_kind(output: Path | None, frames_dir: Path | None, at: float | None) -> str:
    """``mp4``, ``gif``, ``png`` (a still) or ``frames`` from the output options.

    Raises:
        InputError: conflicting options or an unknown extension, naming the option.
    """
    if frames_dir is not None:
        if output is not None:
            raise InputError("give either -o OUT (a movie or still) or --frames DIR, not both",
                             "--frames")
        if at is not None:
            raise InputError("--at renders one still: use -o STILL.png", "--frames")
        return "frames"
    suffix = output.suffix.lower()
    if at is not None:
        if suffix not in STILL_SUFFIXES:
            raise InputError(f"a still (--at) is written as PNG: use a .png name, got "
                             f"'{output.name}'", "-o")
        return STILL_SUFFIXES[suffix]
    if suffix in MOVIE_SUFFIXES:
        return MOVIE_SUFFIXES[suffix]
    if suffix in STILL_SUFFIXES:
        raise InputError(f"'{output.name}' is a still: give --at T (or --frames DIR for every "
                         "frame)", "-o")
    raise InputError(f"unknown movie type '{suffix or output.name}': use .mp4 or .gif, "
                     "--frames DIR for PNG frames, or --at T -o STILL.png", "-o")


def check_size(size: tuple[int, int]) -> tuple[int, int]:
    """The picture size, checked against :data:`MIN_EDGE`/:data:`MAX_EDGE` (``--size``)."""
    width, height = (int(s) for s in size)
    for value in (width, height):
        if not MIN_EDGE <= value <= MAX_EDGE:
            raise InputError(f"width and height must lie in [{MIN_EDGE}, {MAX_EDGE}] px, got "
                             f"{width}x{height}", "--size")
    return width, height


# ---- drawing -----------------------------------------------------------------------------

#: Values of ``--spheres``.
SPHERE_STYLES = ("auto", "mesh", "points")


def check_options(traj, *, camera: str, color_by: str, spheres: str) -> CameraSpec:
    """Check the options that depend on the trajectory before any GL set-up.

    Returns:
        The parsed camera.

    Raises:
        InputError: naming the option.
    """
    if spheres not in SPHERE_STYLES:
        raise InputError(f"unknown value '{spheres}'; choose one of {', '.join(SPHERE_STYLES)}",
                         "--spheres")
    check_color_by(color_by, traj)
    spec = parse_camera(camera)
    check_camera(spec, traj)
    return spec


def wall_planes(traj) -> tuple[list[Plane], str]:
    """The plane walls to draw and the scene's name.

    Both come from the file (the walls as simulated, overrides included). A file written
    before walls were stored has them re-built from its scene text and overrides; if that
    fails (e.g. a scene of another version), a one-line warning goes to stderr and only the
    box is drawn.

    Args:
        traj: A :class:`hsgran.io.h5md.Trajectory`.

    Returns:
        The planes (:class:`hsgran.scene.Plane`) and the scene's name ("" if unknown).
    """
    walls = traj.walls
    if walls is not None:
        motion = walls.motion
        planes = [Plane(walls.point[k], walls.normal[k], int(walls.material[k]), walls.key[k],
                        None if motion is None or motion[k, M_KIND] == MOT_FIXED
                        else motion[k])
                  for k in range(len(walls))
                  if not walls.is_cylinder(k) and not walls.is_part(k)]
        return planes, traj.scene_name
    try:
        # the stored text ends with comment lines naming the overrides, which TOML ignores
        scene = parse_scene(traj.scene_text, overrides=traj.overrides or None)
        return list(scene.planes), scene.name
    except InputError as exc:
        print(f"warning: the file holds no walls (written before they were stored) and its "
              f"scene text does not parse ({exc}): drawing the box only",
              file=sys.stderr)
    planes = []
    if traj.box_lower is not None:
        for axis in range(3):
            if traj.periodic[axis]:
                continue
            for corner, sign in ((traj.box_lower, 1.0), (traj.box_upper, -1.0)):
                normal = np.zeros(3)
                normal[axis] = sign
                planes.append(Plane(np.array(corner, dtype=float), normal, 0, "box"))
    return planes, ""


def wall_cylinders(traj) -> list[Cylinder]:
    """The cylinder walls to draw (:class:`hsgran.scene.Cylinder`), from the file's walls (or
    its scene text, as :func:`wall_planes`)."""
    walls = traj.walls
    if walls is None:
        try:
            return list(parse_scene(traj.scene_text, overrides=traj.overrides or None).cylinders)
        except InputError:
            return []  # wall_planes has warned
    out = []
    for k in range(len(walls)):
        if walls.is_cylinder(k):
            row = walls.cylinder[k]
            out.append(Cylinder(walls.point[k], row[CY_AXIS:CY_AXIS + 3], float(row[CY_RADIUS]),
                                float(row[CY_HALF]), bool(row[CY_SIDE] > 0.0),
                                float(row[CY_OMEGA]), int(walls.material[k]), walls.key[k]))
    return out


def wall_parts(traj) -> list:
    """The parts of the finite walls and the fixed spheres (hsgran.shapes.Part) in the file's
    walls (a file without its walls stored was written before finite walls existed)."""
    walls = traj.walls
    if walls is None:
        return []
    return [walls.part(k) for k in range(len(walls)) if walls.is_part(k)]


def part_meshes(pv, traj) -> list:
    """pyvista meshes of the faces of finite walls and of the fixed spheres (with a cell
    array ``normal`` and ``material``); edges and corners are not drawn."""
    parts = wall_parts(traj)
    if not parts:
        return []
    lower, upper = scene_extent(traj)
    meshes = []
    surfaces = part_surfaces(parts, lower, upper, traj.box_lower, traj.box_upper)
    if surfaces:  # one mesh of every face (a mesh wall has many)
        points, faces, normal, material = [], [], [], []
        start = 0
        for surface in surfaces:
            f = surface.faces.copy()
            k = 0
            while k < len(f):  # shift the corner indices of each polygon
                f[k + 1:k + 1 + f[k]] += start
                normal.append(surface.normal)
                material.append(surface.material)
                k += 1 + f[k]
            points.append(surface.points)
            faces.append(f)
            start += len(surface.points)
        mesh = pv.PolyData(np.concatenate(points), faces=np.concatenate(faces))
        mesh.cell_data["normal"] = np.array(normal, dtype=np.float64)
        mesh.cell_data["material"] = np.array(material, dtype=np.int32)
        meshes.append(mesh)
    for part in parts:
        if part.kind == WK_BALL and part.geo[BL_RADIUS] > 0.0:
            ball = pv.Sphere(radius=float(part.geo[BL_RADIUS]), center=part.point,
                             theta_resolution=FIXED_SPHERE_SEGMENTS,
                             phi_resolution=FIXED_SPHERE_SEGMENTS // 2)
            normal = np.asarray(ball.cell_normals, dtype=np.float64)
            ball.clear_data()  # (float32 "Normals": merged, the cell normals would be dropped)
            ball.cell_data["normal"] = normal
            ball.cell_data["material"] = np.full(ball.n_cells, part.material, dtype=np.int32)
            meshes.append(ball)
    return meshes


class Renderer:
    """Draws frames of one trajectory offscreen.

    Args:
        traj: A :class:`hsgran.io.h5md.Trajectory`.
        size: Width and height [px].
        camera: ``--camera`` value (see :func:`hsgran.animation.parse_camera`).
        color_by: ``speed``, ``state``, ``material`` or ``regime``.
        spheres: ``mesh``, ``points`` (impostors) or ``auto`` (meshes up to
            :data:`MESH_SPHERES_MAX` spheres).
        title: Line above the time label (default: the scene's name).
        time_note: Text after the time (e.g. the slow-motion factor).
        decimals: Decimals of the time label.

    Raises:
        InputError: a bad option value, naming it.
        MissingDependency: pyvista or matplotlib missing.
    """

    def __init__(self, traj, *, size=DEFAULT_SIZE, camera: str = "auto",
                 color_by: str = "speed", spheres: str = "auto", title: str | None = None,
                 time_note: str = "", decimals: int = 4):
        spec = check_options(traj, camera=camera, color_by=color_by, spheres=spheres)
        self.size = check_size(size)
        self.traj = traj
        self.playback = Playback(traj, color_by)
        self.camera_spec = resolve_camera(spec, traj)
        self.mesh_mode = spheres == "mesh" or (spheres == "auto"
                                               and traj.n_particles <= MESH_SPHERES_MAX)
        self.decimals = decimals
        self.time_note = time_note
        planes, name = wall_planes(traj)
        self.title = name if title is None else title

        pv = _import_pyvista()
        import matplotlib

        self._pv = pv
        self._speed_lut = (np.asarray(matplotlib.colormaps[SPEED_CMAP](np.linspace(0, 1, 256)))
                           [:, :3] * 255).astype(np.uint8)
        self._categories = self.playback.categories()
        table = np.zeros((max(self._categories, default=0) + 1, 3), dtype=np.uint8)
        for index, (_, color) in self._categories.items():
            table[index] = np.round(np.array(color) * 255)
        self._category_rgb = table

        self.plotter = pv.Plotter(off_screen=True, window_size=list(self.size))
        self.plotter.ren_win.SetMultiSamples(0)      # anti-aliasing doubles the frame time
        self.plotter.set_background(BACKGROUND)
        self._add_walls(planes)
        self._add_cylinders(wall_cylinders(traj))
        self._add_parts()
        if self.mesh_mode:
            self._add_mesh_spheres()
        else:
            self._add_impostors()
        self._add_annotations()
        self._camera: Camera | None = None

    # -- scene set-up ------------------------------------------------------------------------

    def _add_walls(self, planes: list[Plane]) -> None:
        pv, traj = self._pv, self.traj
        lower, upper = scene_extent(traj)
        spec = self.camera_spec
        if spec.kind == "follow":
            spacing = nice_spacing(2.0 * float(traj.radius[spec.particle]))
        else:
            spacing = nice_spacing(float(np.max(upper - lower)) / 16)
        squares = np.kron(np.array([[0, 1], [1, 0]], dtype=np.uint8),
                          np.ones((CHECKER_TEXELS // 2, CHECKER_TEXELS // 2), dtype=np.uint8))
        image = np.array(CHECKER_COLORS, dtype=np.uint8)[squares]
        texture = pv.Texture(image)
        texture.repeat = True
        texture.interpolate = True
        # No mip-mapping: it costs ~40 ms per full-screen floor in Mesa's software rasteriser,
        # and the low-contrast checker barely shimmers where squares shrink below a pixel.
        texture.mipmap = False
        light = np.asarray(WALL_LIGHT, dtype=float) / np.linalg.norm(WALL_LIGHT)
        self._moving = []  # (actor, plane) of the moving planes, moved at every frame
        patches = wall_patches(planes, lower, upper, traj.box_lower, traj.box_upper)
        for plane, patch in zip(planes, patches, strict=True):
            quad = pv.PolyData(patch.corners, faces=[4, 0, 1, 2, 3])
            # one texture period holds two squares each way
            u, v = patch.edge_u / (2.0 * spacing), patch.edge_v / (2.0 * spacing)
            quad.active_texture_coordinates = np.array([[0, 0], [u, 0], [u, v], [0, v]],
                                                       dtype=float)
            # unlit (VTK's lights cost ~40 ms per full-screen wall in Mesa's software
            # rasteriser), shaded once per wall by a fixed light instead; without lighting
            # VTK multiplies the texture by the colour
            brightness = WALL_AMBIENT + (1.0 - WALL_AMBIENT) * max(0.0, float(patch.normal
                                                                              @ light))
            actor = self.plotter.add_mesh(quad, texture=texture, lighting=False,
                                          color=(brightness,) * 3, show_scalar_bar=False)
            actor.prop.backface_culling = True     # near walls of a box would hide the inside
            if plane.motion is not None:
                self._moving.append((actor, plane))
        if traj.box_lower is not None and not all(traj.periodic):
            bounds = [c for a in range(3) for c in (traj.box_lower[a], traj.box_upper[a])]
            self.plotter.add_mesh(pv.Box(bounds).outline(), color=EDGE_COLOR,
                                  line_width=EDGE_WIDTH)

    def _add_parts(self) -> None:
        """The faces of finite walls (both sides, shaded by a fixed light as the planes) and
        the fixed spheres, in the walls' grey; merged into one mesh (a mesh of many
        triangles, a bed of many fixed spheres)."""
        meshes = part_meshes(self._pv, self.traj)
        if not meshes:
            return
        mesh = meshes[0] if len(meshes) == 1 else self._pv.merge(meshes)
        light = np.asarray(WALL_LIGHT, dtype=float) / np.linalg.norm(WALL_LIGHT)
        shade = WALL_AMBIENT + (1.0 - WALL_AMBIENT) * np.abs(mesh.cell_data["normal"] @ light)
        grey = np.asarray(CHECKER_COLORS[0], dtype=float)
        mesh.cell_data["rgb"] = np.clip(np.outer(shade, grey), 0, 255).astype(np.uint8)
        actor = self.plotter.add_mesh(mesh, scalars="rgb", rgb=True, lighting=False,
                                      show_scalar_bar=False)
        actor.prop.backface_culling = True  # each face of a plate from its own side only

    def _add_cylinders(self, cylinders: list[Cylinder]) -> None:
        """Each cylinder as a tube with stripes along its axis (they show it turn), seen from
        the spheres' side only: the near half of a drum hides nothing."""
        pv = self._pv
        self._turning = []  # (actor, cylinder) of the rotating ones, turned at every frame
        for cyl in cylinders:
            tube = pv.Cylinder(center=cyl.center, direction=cyl.axis, radius=cyl.radius,
                               height=2.0 * cyl.half_length, resolution=CYLINDER_SEGMENTS,
                               capping=False)
            centres = np.asarray(tube.cell_centers().points) - cyl.center
            ref = np.cross(cyl.axis, [1.0, 0.0, 0.0] if abs(cyl.axis[0]) < 0.9
                           else [0.0, 1.0, 0.0])
            angle = np.arctan2(centres @ np.cross(cyl.axis, ref), centres @ ref)
            stripe = np.floor(angle / (2.0 * np.pi) * CYLINDER_STRIPES).astype(int) % 2
            tube.cell_data["rgb"] = np.array(CHECKER_COLORS, dtype=np.uint8)[stripe]
            actor = self.plotter.add_mesh(tube, scalars="rgb", rgb=True, show_scalar_bar=False)
            if cyl.inside:
                actor.prop.frontface_culling = True  # the near half is seen from outside
            else:
                actor.prop.backface_culling = True
            if cyl.angular_velocity != 0.0:
                self._turning.append((actor, cyl))

    def _turn_cylinders(self, t: float) -> None:
        """Turn the rotating cylinders to their angle Ω t at time t [s]."""
        for actor, cyl in self._turning:
            a = np.asarray(cyl.axis, dtype=float)
            phi = cyl.angular_velocity * t
            k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
            rot = np.eye(3) + np.sin(phi) * k + (1.0 - np.cos(phi)) * (k @ k)  # Rodrigues
            m = np.eye(4)
            m[:3, :3] = rot
            m[:3, 3] = cyl.center - rot @ cyl.center
            actor.user_matrix = m

    def _add_mesh_spheres(self) -> None:
        """All spheres in one mesh (one draw call: a VTK actor costs ~1.5 ms per frame in
        Mesa's software rasteriser however small it is), moved vertex by vertex each frame."""
        pv, n = self._pv, self.traj.n_particles
        segments = self._segments()
        template = pv.Sphere(radius=1.0, theta_resolution=segments,
                             phi_resolution=max(MIN_SEGMENTS // 2, (2 * segments) // 3))
        body = np.asarray(template.points, dtype=float)
        # octant parity: the sign pattern of (x, y, z) in the body frame
        odd = np.prod(np.sign(body + 1e-12), axis=1) < 0
        self._shade = np.where(odd, PATTERN_SHADE, 1.0)[None, :, None]
        self._body = body                          # unit sphere: vertices are also normals
        v = body.shape[0]
        faces = template.faces.reshape(-1, 4)      # triangles: [3, a, b, c]
        offsets = (np.arange(n) * v)[:, None, None]
        all_faces = np.concatenate([faces[None, :, :1].repeat(n, 0),
                                    faces[None, :, 1:] + offsets], axis=2)
        self._balls = pv.PolyData(np.zeros((n * v, 3)), faces=all_faces.ravel())
        self._balls.point_data["rgb"] = np.zeros((n * v, 3), dtype=np.uint8)
        self._balls.point_data["Normals"] = np.zeros((n * v, 3))
        self._balls.point_data.active_normals_name = "Normals"
        self._ball_rgb = None
        self.plotter.add_mesh(self._balls, scalars="rgb", rgb=True, specular=0.4,
                              specular_power=30.0, show_scalar_bar=False)

    def _segments(self) -> int:
        """Segments around a sphere mesh for the largest sphere's size on screen (at the
        first frame; the follow camera keeps it, the fixed presets roughly)."""
        first = self.playback.positions(float(self.traj.time[0]))[0]
        cam = camera_at(self.camera_spec, self.traj, self.size,
                        first[self.camera_spec.particle] if self.camera_spec.kind == "follow"
                        else None)
        focal_px = 0.5 * self.size[1] / math.tan(math.radians(cam.view_angle) / 2.0)
        distance = np.linalg.norm(first - cam.position, axis=1) - self.traj.radius
        radius_px = float(np.max(focal_px * self.traj.radius / np.maximum(distance, 1e-300)))
        wanted = 2.0 * math.pi * radius_px / SEGMENT_PIXELS
        affordable = math.sqrt(0.75 * TRIANGLE_BUDGET / self.traj.n_particles)
        # a multiple of 4 puts the octant borders x = 0 and y = 0 on rings of vertices
        segments = 4 * round(min(wanted, affordable) / 4)
        return int(np.clip(segments, MIN_SEGMENTS, MAX_SEGMENTS))

    def _add_impostors(self) -> None:
        pv, n = self._pv, self.traj.n_particles
        self._cloud = pv.PolyData(np.zeros((n, 3)))
        self._cloud.point_data["rgb"] = np.zeros((n, 3), dtype=np.uint8)
        self._cloud.point_data["radius"] = self.traj.radius.astype(float)
        self._markers = pv.PolyData(np.zeros((2 * n, 3)))
        self._markers.point_data["rgb"] = np.zeros((2 * n, 3), dtype=np.uint8)
        self._markers.point_data["radius"] = np.tile(self.traj.radius * MARKER_RADIUS, 2)
        for cloud in (self._cloud, self._markers):
            actor = self.plotter.add_mesh(cloud, style="points_gaussian", scalars="rgb",
                                          rgb=True, emissive=False, show_scalar_bar=False)
            mapper = actor.mapper
            mapper.SetSplatShaderCode(SPHERE_SHADER)
            mapper.SetScaleArray("radius")
            mapper.SetScaleFactor(1.0)       # the splat's radius is the radius array [m]
            # below 1, VTK draws the splats in the (slow, unsorted) translucent pass
            actor.prop.opacity = 1.0

    def _add_annotations(self) -> None:
        height = self.size[1]
        font = max(MIN_FONT, round(height / TEXT_SCALE))
        left = round(0.7 * font)
        self._label = self._text("", left, height - round(2.9 * font), font)
        if self.title:
            self._text(self.title, left, height - round(1.5 * font), font)
        if self.playback.color_by == "speed":
            top = self._speed_max()
            step = nice_step_above(top / SPEED_TICKS)
            bar = self.plotter.add_scalar_bar(
                title="speed [m/s]", cmap=SPEED_CMAP, clim=(0.0, top), vertical=True,
                position_x=0.89, position_y=0.12, width=0.05, height=0.62,
                title_font_size=font, label_font_size=font, color="black",
                n_labels=round(top / step) + 1,
                fmt=f"%.{max(0, -math.floor(math.log10(step) + 1e-9))}f")
            bar.SetVerticalTitleSeparation(font)     # keeps the title off the top label
        else:
            self._add_legend(font)

    def _text(self, text: str, x: int, y: int, font: int):
        actor = self.plotter.add_text(text, position=(x, y), color="black")
        actor.prop.font_size = font              # add_text doubles its font_size argument
        return actor

    def _add_legend(self, font: int) -> None:
        """Coloured disks with black labels in the top right corner (VTK's legend box colours
        the labels like the symbols, which makes light colours unreadable)."""
        from vtkmodules.vtkRenderingCore import vtkActor2D, vtkPolyDataMapper2D

        pv = self._pv
        width, height = self.size
        entries = list(self._categories.values())
        row = round(1.5 * font)
        longest = max(len(label) for label, _ in entries)
        box_w = round(font * (2.2 + 0.6 * longest))
        box_h = row * len(entries) + font // 2
        x0, y0 = width - box_w - font, height - box_h - font

        def disk(x, y, radius, color, opacity=1.0, sides=32):
            shape = pv.Polygon(center=(x, y, 0.0), radius=radius, n_sides=sides)
            mapper = vtkPolyDataMapper2D()
            mapper.SetInputData(shape)
            actor = vtkActor2D()
            actor.SetMapper(mapper)
            actor.GetProperty().SetColor(*color)
            actor.GetProperty().SetOpacity(opacity)
            self.plotter.renderer.AddViewProp(actor)

        background = pv.PolyData(np.array([[x0, y0, 0.0], [x0 + box_w, y0, 0.0],
                                           [x0 + box_w, y0 + box_h, 0.0],
                                           [x0, y0 + box_h, 0.0]]), faces=[4, 0, 1, 2, 3])
        mapper = vtkPolyDataMapper2D()
        mapper.SetInputData(background)
        panel = vtkActor2D()
        panel.SetMapper(mapper)
        panel.GetProperty().SetColor(1.0, 1.0, 1.0)
        panel.GetProperty().SetOpacity(LEGEND_OPACITY)
        self.plotter.renderer.AddViewProp(panel)
        for k, (label, color) in enumerate(entries):
            y = y0 + box_h - round(font * 0.25) - row * k - row // 2
            disk(x0 + font, y, 0.45 * font, color)
            self._text(label, x0 + round(1.9 * font), y - round(0.4 * font), font)

    def _speed_max(self) -> float:
        """Top of the speed scale [m/s]: the fastest sphere's speed rounded up to a multiple of
        a 1-2-5 step, so that the colour bar's labels are round numbers."""
        fastest = self.playback.speed_max if self.playback.speed_max > 0.0 else 1.0
        step = nice_step_above(fastest / SPEED_TICKS)
        return step * math.ceil(fastest / step * (1.0 - 1e-9))

    # -- per frame ---------------------------------------------------------------------------

    def colors(self, values: np.ndarray) -> np.ndarray:
        """RGB [0-255] of every sphere, shape (N, 3), uint8, from the colour variable."""
        if self.playback.color_by == "speed":
            index = np.clip(values / self._speed_max() * 255.0, 0, 255).astype(np.int64)
            return self._speed_lut[index]
        return self._category_rgb[values]

    def camera(self, frame: FrameState) -> Camera:
        """The camera of a frame (:func:`hsgran.animation.camera_at`)."""
        spec = self.camera_spec
        followed = frame.position[spec.particle] if spec.kind == "follow" else None
        if spec.kind != "follow" and self._camera is not None:
            return self._camera
        self._camera = camera_at(spec, self.traj, self.size, followed)
        return self._camera

    def draw(self, frame: FrameState) -> np.ndarray:
        """Draw one frame.

        Args:
            frame: What to draw (:meth:`hsgran.animation.Playback.frame`).

        Returns:
            The picture, (height, width, 3) uint8.
        """
        rgb = self.colors(frame.values)
        for actor, plane in self._moving:
            actor.position = tuple(plane.point_at(frame.time) - plane.point)
        self._turn_cylinders(frame.time)
        if self.mesh_mode:
            self._update_meshes(frame, rgb)
        else:
            self._update_impostors(frame, rgb)
        self._label.input = f"t = {frame.time:.{self.decimals}f} s{self.time_note}"
        cam = self.camera(frame)
        vtk_camera = self.plotter.camera
        vtk_camera.position = tuple(cam.position)
        vtk_camera.focal_point = tuple(cam.focal_point)
        vtk_camera.up = tuple(cam.view_up)
        vtk_camera.view_angle = cam.view_angle
        self.plotter.renderer.ResetCameraClippingRange()
        self.plotter.render()
        return np.asarray(self.plotter.screenshot(return_img=True))[..., :3]

    def _update_meshes(self, frame: FrameState, rgb: np.ndarray) -> None:
        # normals of a unit sphere's vertices are the rotated vertices themselves
        normals = np.einsum("kij,vj->kvi", frame.rotation, self._body)
        radius = self.traj.radius * frame.shown  # a sphere not in the system: a point
        points = (normals * radius[:, None, None]
                  + frame.position[:, None, :]).reshape(-1, 3)
        self._balls.points[:] = points
        self._balls.point_data["Normals"][:] = normals.reshape(-1, 3)
        if self._ball_rgb is None or np.any(self._ball_rgb != rgb):
            shaded = np.round(rgb[:, None, :] * self._shade).astype(np.uint8)
            self._balls.point_data["rgb"][:] = shaded.reshape(-1, 3)
            self._ball_rgb = rgb.copy()
        self._balls.Modified()

    def _update_impostors(self, frame: FrameState, rgb: np.ndarray) -> None:
        n = self.traj.n_particles
        self._cloud.points[:] = frame.position
        self._cloud.point_data["rgb"][:] = rgb
        # a sphere not in the system is a splat of radius 0: not drawn
        shown = self.traj.radius * frame.shown
        self._cloud.point_data["radius"][:] = shown
        self._markers.point_data["radius"][:] = np.tile(shown * MARKER_RADIUS, 2)
        self._cloud.Modified()
        axis = np.asarray(MARKER_AXIS, dtype=float) / np.linalg.norm(MARKER_AXIS)
        offset = (frame.rotation @ axis) * (MARKER_OFFSET * self.traj.radius)[:, None]
        self._markers.points[:n] = frame.position + offset
        self._markers.points[n:] = frame.position - offset
        luma = rgb.astype(float) @ np.array([0.2126, 0.7152, 0.0722]) / 255.0
        marker = np.where((luma > MARKER_LUMA_SPLIT)[:, None], np.array(MARKER_DARK),
                          np.array(MARKER_LIGHT)).astype(np.uint8)
        self._markers.point_data["rgb"][:] = np.tile(marker, (2, 1))
        self._markers.Modified()

    def close(self) -> None:
        """Release the render window."""
        self.plotter.close()


# ---- output ------------------------------------------------------------------------------

class _Sink:
    """Writes frames to a temporary file or folder beside the target; :meth:`commit` renames
    it to the target, :meth:`abort` removes it."""

    def __init__(self, kind: str, target: Path, fps: float):
        self.kind, self.target, self.fps = kind, target, fps
        self.count = 0
        parent = target.parent
        if kind == "frames":
            self.tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".part",
                                             dir=parent))
            _as_if_created(self.tmp, 0o777)
            self._writer = None
            return
        handle, name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=f".part{target.suffix}",
                                        dir=parent)
        os.close(handle)
        self.tmp = Path(name)
        _as_if_created(self.tmp, 0o666)
        import imageio.v2 as iio2

        if kind == "mp4":
            self._writer = iio2.get_writer(
                self.tmp, format="FFMPEG", mode="I", fps=fps, codec="libx264",
                quality=MP4_QUALITY, pixelformat="yuv420p", macro_block_size=MP4_BLOCK,
                ffmpeg_log_level="error")
        else:
            self._writer = None
        self._gif_frames = []

    def write(self, image: np.ndarray) -> None:
        import imageio.v3 as iio

        if self.kind == "mp4":
            self._writer.append_data(image)
        elif self.kind == "gif":
            from PIL import Image

            # one palette per frame; "max coverage" keeps the small, saturated legend disks and
            # spheres their colours where the default (median cut) spends the palette on the
            # large grey floor
            self._gif_frames.append(Image.fromarray(image).quantize(
                colors=256, method=Image.Quantize.MAXCOVERAGE, dither=Image.Dither.NONE))
        elif self.kind == "frames":
            iio.imwrite(self.tmp / FRAME_PATTERN.format(self.count), image)
        else:
            iio.imwrite(self.tmp, image, extension=".png")
        self.count += 1

    def commit(self) -> None:
        self._close_writer()
        if self.kind == "gif":
            first, *rest = self._gif_frames
            # GIF stores delays in hundredths of a second; pillow takes milliseconds
            first.save(self.tmp, format="GIF", save_all=True, append_images=rest, loop=0,
                       duration=10 * round(100.0 / self.fps))
            self._gif_frames = []
        if self.kind != "frames":
            os.replace(self.tmp, self.target)
            return
        if self.target.exists():
            for old in self.target.glob("frame_*.png"):
                old.unlink()
            for new in sorted(self.tmp.iterdir()):
                os.replace(new, self.target / new.name)
            self.tmp.rmdir()
        else:
            os.replace(self.tmp, self.target)

    def abort(self) -> None:
        with contextlib.suppress(Exception):
            self._close_writer()
        if self.tmp.is_dir():
            shutil.rmtree(self.tmp, ignore_errors=True)
        else:
            with contextlib.suppress(FileNotFoundError):
                self.tmp.unlink()

    def _close_writer(self) -> None:
        if self._writer is not None:
            writer, self._writer = self._writer, None
            writer.close()


def _as_if_created(path, mode: int) -> None:
    """Give a temporary file or folder the permissions a plain open() or mkdir() would have
    (mkstemp and mkdtemp make them private to the owner)."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(path, mode & ~umask)


def check_target(kind: str, target: Path, force: bool) -> None:
    """Refuse to overwrite without ``force``, and a frame folder holding anything but frames.

    Raises:
        InputError: naming the output option.
    """
    option = "--frames" if kind == "frames" else "-o"
    if not target.parent.is_dir():
        raise InputError(f"folder {target.parent} does not exist", option)
    if kind == "frames":
        if target.exists() and not target.is_dir():
            raise InputError(f"{target} exists and is not a folder", option)
        if target.is_dir():
            others = [p.name for p in target.iterdir() if not p.match("frame_*.png")]
            if others:
                raise InputError(f"{target} holds other files than frame_*.png "
                                 f"({others[0]}, ...): choose an empty or new folder", option)
            if any(target.iterdir()) and not force:
                raise InputError(f"{target} already holds frames: pass --force to replace "
                                 "them", option)
        return
    if target.is_dir():
        raise InputError(f"{target} is a folder", option)
    if target.exists() and not force:
        raise InputError(f"{target} exists: pass --force to overwrite it", option)


def _time_note(kind: str, time_scale: float) -> str:
    if kind == "png" or math.isclose(time_scale, 1.0, rel_tol=1e-3):
        return ""
    if time_scale < 1.0:
        return f"   ({1.0 / time_scale:.3g}x slow motion)"
    return f"   ({time_scale:.3g}x real time)"


def render(trajectory, output=None, *, frames_dir=None, at: float | None = None,
           fps: float = DEFAULT_FPS, size=DEFAULT_SIZE, camera: str = "auto",
           color_by: str = "speed", time_scale: float | None = None,
           start: float | None = None, end: float | None = None, spheres: str = "auto",
           force: bool = False, progress: bool = False) -> RenderResult:
    """Render a trajectory file offscreen to a movie, PNG frames or one still.

    Args:
        trajectory: HDF5 trajectory written by ``hsgran run``.
        output: ``.mp4`` or ``.gif`` movie, or ``.png`` still with ``at``; default: the
            trajectory's name with ``.mp4`` (``.png`` with ``at``).
        frames_dir: Folder for PNG frames instead of ``output``.
        at: Simulated time [s] of a single still.
        fps: Frames per second of video [1/s].
        size: Width and height [px] (MP4: rounded up to multiples of 16).
        camera: ``auto``, ``iso``, ``side``, ``top``, ``follow:K``, ``X,Y,Z`` or
            ``X,Y,Z:FX,FY,FZ`` [m].
        color_by: ``speed``, ``state``, ``material`` or ``regime``.
        time_scale: Simulated seconds per second of video [-]; default: one movie frame per
            stored frame.
        start, end: Simulated time range [s] of a movie.
        spheres: ``auto``, ``mesh`` or ``points`` (see :class:`Renderer`).
        force: Overwrite an existing output.
        progress: Show a progress bar over frames (stderr).

    Returns:
        A :class:`RenderResult`.

    Raises:
        InputError: bad option value, unreadable or non-hsgran trajectory, missing system
            libraries; one line.
        MissingDependency: the render extra is not installed.
    """
    if not math.isfinite(fps) or fps <= 0.0:
        raise InputError(f"must be a finite number > 0, got {fps!r}", "--fps")
    if time_scale is not None and (not math.isfinite(time_scale) or time_scale <= 0.0):
        raise InputError(f"must be a finite number > 0, got {time_scale!r}", "--time-scale")
    path = Path(trajectory)
    frames_dir = None if frames_dir is None else Path(frames_dir)
    if output is None and frames_dir is None:
        output = path.with_suffix(".png" if at is not None else ".mp4")
    output = None if output is None else Path(output)
    kind = output_kind(output, frames_dir, at)
    target = frames_dir if kind == "frames" else output
    width, height = check_size(size)
    if kind == "mp4" and (width % MP4_BLOCK or height % MP4_BLOCK):
        width, height = (-(-width // MP4_BLOCK) * MP4_BLOCK, -(-height // MP4_BLOCK) * MP4_BLOCK)
        print(f"note: MP4 frames are multiples of {MP4_BLOCK} px: rendering {width}x{height}",
              file=sys.stderr)
    traj = read_trajectory(path)
    if traj.n_frames == 0:
        raise InputError(f"{path} has no frames")
    times = sample_times(traj.time, fps=fps, time_scale=time_scale, start=start, end=end, at=at)
    scale = time_scale if time_scale is not None else (
        float(times[1] - times[0]) * fps if times.shape[0] > 1 else 1.0)
    check_options(traj, camera=camera, color_by=color_by, spheres=spheres)
    check_target(kind, target, force)
    problem = missing_system_libraries()
    if problem:
        raise InputError(problem)
    renderer = Renderer(traj, size=(width, height), camera=camera, color_by=color_by,
                        spheres=spheres, time_note=_time_note(kind, scale),
                        decimals=time_label_decimals(times, traj.time))
    from tqdm import tqdm

    sink = _Sink(kind, target, fps)
    drawing = 0.0
    try:
        for t in tqdm(times, unit="frame", desc="render", disable=not progress,
                      dynamic_ncols=True):
            t0 = _time.perf_counter()
            image = renderer.draw(renderer.playback.frame(float(t)))
            drawing += _time.perf_counter() - t0
            sink.write(image)
        sink.commit()
    except BaseException:
        sink.abort()
        raise
    finally:
        renderer.close()
    return RenderResult(output=target, kind=kind, frames=int(times.shape[0]),
                        size=(width, height), fps=fps, time_scale=scale,
                        seconds_per_frame=drawing / max(1, times.shape[0]))
