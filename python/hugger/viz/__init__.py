"""Figures and animations of a plan (matplotlib): the paper's Fig. 4 and Fig. 5, a TipState plot,
GIF/MP4 animations, and :func:`render`, which the command line calls. :func:`view` (an interactive
3D view in the browser) and :func:`export_scene` (a glTF scene) come from :mod:`hugger.viewer`.

Needs the ``viz`` extra (``pip install 'hugger[viz]'``: matplotlib and Pillow); MP4 also needs an
ffmpeg binary (the ``imageio-ffmpeg`` package, or ``ffmpeg`` on the ``PATH``). Nothing here is
imported by ``import hugger``; matplotlib is imported when a function is first called, and the
non-interactive Agg backend is selected then, only if no backend has been chosen yet.

What the pictures show
----------------------
The object O is a semi-transparent, light-shaded mesh (meshes over ``max_faces`` triangles are
simplified for drawing only); each link is a capsule of the link radius; the palm is a disc of
``palm_radius`` and ``palm_thickness`` whose front face is at the palm origin P_o; T is a black
cross; contacts are red dots, drawn on top of everything. Zero-radius links (the paper's) are
drawn as thin tubes (4% of the mean link length) with dark beads at the joints: a thick line
that is still depth-sorted with the object and the palm. Fingers are coloured by their TipState
at that configuration: FROZEN blue, CONTACT orange, DONE green.

Contacts are those of :func:`hugger.analysis.contacts` (gap at most ``CONTACT_DISTANCE``, 1 mm).

The camera is fixed to the *final* palm pose, not to the world: every 3D view is drawn in a
"display frame" centred on T, in which the final palm normal p-hat points down the screen (the
display -z axis) and finger 0 along the display x axis, so the grasp reads the same whichever
way the hand approached. Axes are hidden
(the figures are about shape, as in the paper); lengths in the titles are in millimetres.
Configuration indices ``k`` count from 0 (C_init) to K-1, as in the trajectory file.
Resolutions are from :data:`MIN_DPI` to :data:`MAX_DPI` (10 to 1200 dots per inch), frame rates at most :data:`MAX_FPS`
(120 a second), and an animation's final pause at most :data:`MAX_HOLD` (10 s).

The parts: :mod:`~hugger.viz.backend` (matplotlib, ffmpeg and argument checks),
:mod:`~hugger.viz.scene` (drawing one configuration), :mod:`~hugger.viz.figures` (Fig. 4, Fig. 5, the
overview sheet, the TipState plot, :data:`FIGURES` and :func:`render`) and :mod:`~hugger.viz.animation` (GIF and MP4);
every name is available here, as ``hugger.viz.<name>``.
"""
from __future__ import annotations

import shutil as shutil  # hugger.viz.shutil: ffmpeg_path() finds ffmpeg with shutil.which

from .._types import CONTACT_DISTANCE
from ..viewer import export_scene, view  # the 3D viewer and glTF export (extra: view), hugger.viz.view
from .animation import MOVIE_SIZE as MOVIE_SIZE, animate
from .backend import RENDER_SUFFIXES, _MOVIE_EXTENSIONS as _MOVIE_EXTENSIONS, _STILL_EXTENSIONS as _STILL_EXTENSIONS
from .backend import _VIZ_EXTRA as _VIZ_EXTRA, _backend_unset as _backend_unset, _check_faces as _check_faces
from .backend import _check_still as _check_still, _check_traj as _check_traj, _ffmpeg as _ffmpeg
from .backend import _pyplot as _pyplot, _save as _save, _suffix as _suffix, ffmpeg_path, require
from .backend import MAX_DPI, MAX_FPS, MAX_HOLD, MIN_DPI, check_dpi, check_fps
from .figures import FIG4_SIZE as FIG4_SIZE, FIG5_SIZE as FIG5_SIZE, OVERVIEW_SIZE as OVERVIEW_SIZE
from .figures import TIPSTATE_SIZE as TIPSTATE_SIZE, _contact_caption as _contact_caption
from .figures import _fig4_axes as _fig4_axes, _fig4_panels as _fig4_panels, _fig5_axes as _fig5_axes
from .figures import _first_contact as _first_contact, _headline as _headline, _still as _still
from .figures import FIGURES, fig4, fig5, overview, pick_figure, render, tipstate_plot
from .scene import STATE_COLORS, _ALONG_NORMAL as _ALONG_NORMAL, _Box as _Box, _CONTACT_COLOR as _CONTACT_COLOR
from .scene import _OBJECT_ALPHA as _OBJECT_ALPHA, _OBJECT_RGB as _OBJECT_RGB, _OBLIQUE as _OBLIQUE
from .scene import _PALM_RGB as _PALM_RGB, _SIDE as _SIDE, _SPHERE_NORMALS as _SPHERE_NORMALS
from .scene import _SPHERE_QUADS as _SPHERE_QUADS, _STATE_NAMES as _STATE_NAMES, _Scene as _Scene
from .scene import _VIEWS as _VIEWS, _View as _View, _camera as _camera, _contact_points as _contact_points
from .scene import _decimate as _decimate, _frame as _frame, _hand_polys as _hand_polys, _legend as _legend
from .scene import _palm_polys as _palm_polys, _phase_name as _phase_name, _rgb as _rgb, _ring as _ring
from .scene import _setup_axes as _setup_axes, _shade as _shade, _subsample as _subsample, _tube as _tube
from .scene import _unit_sphere as _unit_sphere, draw_configuration

__all__ = ["CONTACT_DISTANCE", "FIGURES", "MAX_DPI", "MAX_FPS", "MAX_HOLD", "MIN_DPI", "RENDER_SUFFIXES", "STATE_COLORS", "animate",
           "check_dpi", "check_fps", "draw_configuration", "export_scene", "ffmpeg_path", "fig4", "fig5", "overview",
           "pick_figure", "render", "require", "tipstate_plot", "view"]
