"""Figures and animations of a Result (matplotlib, imported only here; docs/scenes.md,
"Figures").  Every figure has a title and units on its axes; angles are unwrapped.

    plot_positions(result)      the bodies' output points, x, y, z against t
    plot_angles(result)         the x-y-z angles of each body, unwrapped
    plot_energy(result)         kinetic, potential, total, and the total's change
    plot_joints(result)         joint coordinates and drive forces (joints with coordinates)
    plot_modal(result)          the beams' modal and the strain rods' strain coordinates
    run_figures(result, model, directory)   all that apply, as PNG files
    animate(result, model, path)            a 3D animation, GIF (Pillow) or MP4 (ffmpeg)
"""
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from ..elements.beam import FAMILY, LENGTH, MODES, STIFFENING, mode_shapes, stretch_along
from ..elements.kinds import BEAM, RIGID, ROD, unimplemented_body_kind
from ..model.rod_motion import rod_centre_line
from .feedback import Progress
from ..model.sections import foreshortening_along


def _plt():
    try:
        import matplotlib
    except ImportError:
        raise ImportError("dttmm's figures and animations need matplotlib: "
                          "pip install 'dttmm[plots]'") from None
    if matplotlib.get_backend().lower() not in ("agg", "module://matplotlib_inline.backend_inline"):
        try:
            matplotlib.use("Agg")
        except Exception:               # an interactive session keeps its backend
            pass
    import matplotlib.pyplot as plt
    return plt


def _axes(ax, rows=1, figsize=(8, 6)):
    plt = _plt()
    if ax is not None:
        return ax.figure, np.atleast_1d(ax)
    fig, axes = plt.subplots(rows, 1, figsize=figsize, sharex=True, squeeze=False,
                             constrained_layout=True)
    return fig, axes[:, 0]


def _names(result):
    n = result.rotation.shape[1]
    return result.body_names or tuple(f"body{k}" for k in range(n))      # (as Model names them)


def _finish(fig, axes, title, legend_columns=4):
    """Grid on every axis, the legend on the first, t (s) under the last, the title."""
    for a in axes:
        a.grid(alpha=0.3)
    axes[0].legend(fontsize="small", ncol=legend_columns)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle(title)
    return fig


def _per_component(result, values, ax, ylabel, title):
    """values (T, n, 3): one axis per component, each body a line, so that a small component
    is not flattened by a large one; ylabel formats the component's letter."""
    fig, axes = _axes(ax, 3)
    for c, a in enumerate(axes[:3]):
        for k, name in enumerate(_names(result)):
            a.plot(result.t, values[:, k, c], label=name)
        a.set_ylabel(ylabel.format("xyz"[c]))
    return _finish(fig, axes, title)


def plot_positions(result, ax=None, point="output", title=None):
    """x, y, z (m) of each body's point ("output", "input" or "mass_center") against t (s),
    one axis per component."""
    return _per_component(result, getattr(result, f"position_{point}"), ax, "{} (m)",
                          title or f"{point.replace('_', ' ')} points")


def plot_angles(result, ax=None, title=None):
    """The space-fixed x-y-z angles (rad) of each body, A = Rz Ry Rx, unwrapped over time."""
    return _per_component(result, np.unwrap(result.xyz_angles, axis=0), ax, "theta_{} (rad)",
                          title or "x-y-z angles (unwrapped)")


def _column_labels(result, key, letter, count):
    """The columns' legend names from result.info[key] (run_tables.column_names), else letter1,
    letter2, ..."""
    names = (result.info or {}).get(key)
    return list(names) if names is not None and len(names) == count else [
        f"{letter}{j + 1}" for j in range(count)]


def _style(j):
    """Line j's colour and dash: the 10 colours of the cycle, then again dashed, dotted, ...
    (no two lines of up to 40 look alike)."""
    return dict(color=f"C{j % 10}", linestyle=("-", "--", ":", "-.")[(j // 10) % 4])


def plot_energy(result, ax=None, title=None):
    """Kinetic, potential and total energy (J), and the total's change from t = 0 on an axis
    of its own (a drift of 1e-9 J is invisible beside energies of joules); where the run kept
    the energy balance (result.energy_work), the balance E - E(0) - W beside it, W the work
    of loads, drives, dampers and a moving ground."""
    fig, axes = _axes(ax, 2)
    axes[0].plot(result.t, result.kinetic, label="kinetic")
    axes[0].plot(result.t, result.potential, label="potential")
    axes[0].plot(result.t, result.total_energy, label="total")
    axes[0].set_ylabel("energy (J)")
    change = result.total_energy - result.total_energy[0]
    if result.energy_work is None:
        axes[1].plot(result.t, change, color="k")
        axes[1].set_ylabel("total - total(0) (J)")
    else:       # the work done on the system apart: what is left is the integrator's error
        axes[1].plot(result.t, change, color="0.6", linestyle="--",
                     label="E - E(0): with the work done on it")
        axes[1].plot(result.t, change - result.energy_work, color="k",
                     label="balance E - E(0) - W")
        axes[1].set_ylabel("energy change (J)")
        axes[1].legend(fontsize="small")
    return _finish(fig, axes, title or "energy", legend_columns=1)


def plot_joints(result, ax=None, title=None):
    """Joint coordinates (rad or m) and the drives' generalized forces (N m or N): the second
    panel only for the coordinates a drive acts on (an undriven joint's force is zero by
    construction: its rounding, ~1e-14, is not drawn), and only where there are some."""
    if result.joint_coordinates is None:
        raise ValueError("plot_joints: the result has no joints with coordinates")
    names = _column_labels(result, "coordinate_names", "q", result.joint_coordinates.shape[1])
    force = np.asarray(result.drive_force)
    driven = [j for j in range(len(names))
              if np.abs(force[:, j]).max(initial=0.0) > ZERO_FORCE * max(
                  1.0, float(np.abs(force).max(initial=0.0)))]
    fig, axes = _axes(ax, 2 if driven else 1)
    for j, name in enumerate(names):
        axes[0].plot(result.t, result.joint_coordinates[:, j], label=name, **_style(j))
    for j in driven:
        axes[1].plot(result.t, force[:, j], label=names[j], **_style(j))
    axes[0].set_ylabel("coordinate (rad or m)")
    if driven:
        axes[1].set_ylabel("drive force (N m or N)")
    return _finish(fig, axes, title or "joints")


ZERO_FORCE = 1e-9     # of the largest drive force (or 1 N): below it a column is rounding


def plot_contacts(result, model=None, ax=None, title=None):
    """The contact forces (docs/contact.md) against t: the normal force (N, along the plane's
    normal) and the friction force's size (N), summed over each body's contact spheres (per
    sphere without the model, whose Model.contacts names their bodies)."""
    if result.contact_force is None:
        raise ValueError("plot_contacts: the result has no contact shapes")
    force, normal = np.asarray(result.contact_force), np.asarray(result.contact_normal)
    along = np.einsum("tci,tci->tc", force, normal)
    across = np.linalg.norm(force - along[:, :, None] * normal, axis=2)
    if model is not None:
        owner = np.asarray(model.contacts)[:, 0].astype(int)
        groups = [(model.body_names[k], owner == k) for k in dict.fromkeys(owner)]
    else:
        groups = [(f"sphere {c}", np.arange(force.shape[1]) == c)
                  for c in range(force.shape[1])]
    fig, axes = _axes(ax, 2)
    for j, (name, mine) in enumerate(groups):
        axes[0].plot(result.t, along[:, mine].sum(axis=1), label=name, **_style(j))
        axes[1].plot(result.t, across[:, mine].sum(axis=1), label=name, **_style(j))
    axes[0].set_ylabel("normal force (N)")
    axes[1].set_ylabel("friction force (N)")
    return _finish(fig, axes, title or "contact forces")


def plot_modal(result, ax=None, title=None):
    """The beams' modal coordinates eta (m, mode shapes of unit amplitude) and the strain rods'
    strain coefficients (1/m for curvatures and twist, 1 for stretch) against t."""
    if result.modal_coordinates is None:
        raise ValueError("plot_modal: the result has no beams or strain rods")
    fig, axes = _axes(ax, 1)
    names = _column_labels(result, "modal_names", "eta", result.modal_coordinates.shape[1])
    for j, name in enumerate(names):
        axes[0].plot(result.t, result.modal_coordinates[:, j], label=name, **_style(j))
    default_title, label = _modal_words(names)
    axes[0].set_ylabel(label)
    return _finish(fig, axes, title or default_title)


def _modal_words(names):
    """(title, y label) of plot_modal for its columns' names (run_tables.column_names: a strain
    rod's columns are its components bend_z, bend_y, twist, stretch with their numbers)."""
    rods = {n.rsplit(" ", 1)[0] for n in names if n.rsplit(" ", 1)[-1].startswith("bend_")}
    beams = any(n.rsplit(" ", 1)[0] not in rods for n in names)
    if rods and beams:
        return ("beams' modal and strain rods' strain coordinates",
                "modal coordinate (m), strain coefficient (1/m; stretch 1)")
    if rods:
        return "strain rods' strain coordinates", "strain coefficient (1/m; stretch 1)"
    return "beams' modal coordinates", "modal coordinate (m)"


def run_figures(result, model, directory, title=""):
    """Every figure that applies to the run, as PNG files in directory; returns their paths."""
    plt = _plt()
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    prefix = f"{title}: " if title else ""
    figures = [("positions", plot_positions(result, title=prefix + "output points")),
               ("angles", plot_angles(result, title=prefix + "x-y-z angles (unwrapped)")),
               ("energy", plot_energy(result, title=prefix + "energy"))]
    if result.joint_coordinates is not None:
        figures.append(("joints", plot_joints(result, title=prefix + "joints")))
    if result.contact_force is not None:
        figures.append(("contacts", plot_contacts(result, model,
                                                  title=prefix + "contact forces")))
    if result.modal_coordinates is not None:
        names = _column_labels(result, "modal_names", "eta", result.modal_coordinates.shape[1])
        figures.append(("modal", plot_modal(result, title=prefix + _modal_words(names)[0])))
    paths = []
    for name, fig in figures:
        path = directory / f"{name}.png"
        fig.savefig(path, dpi=90)
        plt.close(fig)
        paths.append(path)
    return paths


def centerlines(result, model, points=12):
    """(T, n, points, 3) world points along every body: a rigid body's input, mass centre and
    output points (repeated), a beam's deflected centreline r_I + A ((x - c(x) + s(x)) e1 + u)
    (docs/beam.md; c the foreshortening of a stiffened beam, s the stretch), a strain rod's
    centre line from its strain (elements/strain_rod.py::rod_centre_line), ending on its output
    point."""
    n = model.n_bodies
    out = np.empty((len(result.t), n, points, 3))
    offsets = np.concatenate([[0], np.cumsum(model.n_modes)])
    for k in range(n):
        r_in = result.position_input[:, k]
        if model.body_kind[k] == BEAM:
            row = model.beam_params[k]
            m, length = int(row[MODES]), row[LENGTH]
            x = np.linspace(0.0, length, points)
            y = mode_shapes(int(row[FAMILY]), length, m, x)[0]
            eta = result.modal_coordinates[:, offsets[k]:offsets[k + 1]]
            local = np.zeros((len(result.t), points, 3))
            local[:, :, 0] = x + stretch_along(row, eta, x)
            if row[STIFFENING]:
                local[:, :, 0] -= foreshortening_along(row, x, eta, eta)[0]
            local[:, :, 1] = eta[:, :m] @ y
            local[:, :, 2] = eta[:, m:2 * m] @ y
            out[:, k] = r_in[:, None] + np.einsum("tij,tpj->tpi", result.rotation[:, k], local)
        elif model.body_kind[k] == ROD:
            local = rod_centre_line(model.rod_params[k],
                                    result.modal_coordinates[:, offsets[k]:offsets[k + 1]],
                                    points)
            out[:, k] = r_in[:, None] + np.einsum("tij,tpj->tpi", result.rotation[:, k], local)
            out[:, k, -1] = result.position_output[:, k]
        elif model.body_kind[k] == RIGID:
            s = np.linspace(0.0, 1.0, points)[None, :, None]
            r_c, r_o = result.position_mass_center[:, k], result.position_output[:, k]
            first = np.where(s <= 0.5, r_in[:, None] + 2 * s * (r_c - r_in)[:, None],
                             r_c[:, None] + (2 * s - 1) * (r_o - r_c)[:, None])
            out[:, k] = first
        else:
            raise unimplemented_body_kind(model.body_kind[k], f"body '{model.body_names[k]}'",
                                          "the figures' centre lines (results/plots.py)")
    return out


def animate(result, model, path, title="", frames=150, fps=25, progress=None, view="auto"):
    """A 3D animation of the run (each body a line through its points, a beam its deflected
    centreline) to path: .gif (Pillow, with matplotlib) or .mp4 (ffmpeg needed).  The axes
    are drawn once and each frame draws only the bodies and the time over them (blitting); a
    GIF's frames share the first frame's palette.  progress: a bar over the frames (None:
    when stderr is a terminal).  view: "auto" (default: a planar motion seen square on, along
    its plane's normal, else an oblique view), "oblique", "xy", "xz", "yz" (the world plane
    seen square on), or (elevation, azimuth) in degrees (matplotlib's, in the drawn axes,
    whose z is against gravity)."""
    plt = _plt()
    from matplotlib import animation
    path = Path(path)
    if path.suffix not in (".gif", ".mp4"):
        raise ValueError(f"animate: {path}: write a .gif or an .mp4")
    pick = np.unique(np.linspace(0, len(result.t) - 1, min(frames, len(result.t))).astype(int))
    lines = centerlines(_samples(result, pick), model)
    pick = np.arange(len(pick))
    # the world axis against gravity is drawn upwards (matplotlib's z)
    g = np.asarray(model.gravity, dtype=float)
    up = int(np.argmax(np.abs(g))) if np.any(g) else 2
    order = [i for i in range(3) if i != up] + [up]
    sign = np.array([1.0, 1.0, -1.0 if g[up] > 0 else 1.0])
    lines = lines[..., order] * sign
    labels = [f"{'-' if sign[j] < 0 else ''}{'xyz'[order[j]]} (m)" for j in range(3)]
    times = result.t[np.unique(np.linspace(0, len(result.t) - 1,
                                           min(frames, len(result.t))).astype(int))]
    lo, hi = lines.reshape(-1, 3).min(axis=0), lines.reshape(-1, 3).max(axis=0)
    mid, half = 0.5 * (lo + hi), 0.5 * max(float(np.max(hi - lo)), 1e-9) * 1.1
    fig = plt.figure(figsize=(6, 6))
    ax = fig.add_subplot(projection="3d")
    ax.set_box_aspect((1, 1, 1))
    elevation, azimuth = view_angles(lines.reshape(-1, 3), view, order)
    ax.view_init(elev=elevation, azim=azimuth)
    e, a = np.radians(elevation), np.radians(azimuth)
    sight = np.abs([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    for i, set_lim in enumerate((ax.set_xlim, ax.set_ylim, ax.set_zlim)):
        set_lim(mid[i] - half, mid[i] + half)
        if sight[i] > 0.999:        # seen along this axis: its ticks would pile up
            (ax.set_xticks, ax.set_yticks, ax.set_zticks)[i]([])
            continue
        (ax.set_xlabel, ax.set_ylabel, ax.set_zlabel)[i](labels[i])
    drawn = [ax.plot([], [], [], lw=2, marker="o", markevery=[0])[0]
             for _ in range(model.n_bodies)]
    stamp = ax.set_title("")

    def frame(j):
        i = pick[j]
        for k, line in enumerate(drawn):
            line.set_data_3d(lines[i, k, :, 0], lines[i, k, :, 1], lines[i, k, :, 2])
        stamp.set_text(f"{title + ': ' if title else ''}t = {times[i]:.3f} s")
        return drawn

    bar = Progress(len(pick), progress, what="animation", unit="frame")
    try:
        if path.suffix == ".gif":
            _write_gif(fig, ax, drawn + [stamp], frame, len(pick), fps, path, bar)
        else:
            anim = animation.FuncAnimation(fig, frame, frames=len(pick), interval=1000 / fps)
            anim.save(path, writer=animation.FFMpegWriter(fps=fps),
                      progress_callback=lambda i, n: bar.update(i + 1))
    finally:
        bar.close()
        plt.close(fig)
    return path


VIEWS = ("auto", "oblique", "xy", "xz", "yz")
PLANAR = 1e-3      # a motion whose points spread less than this fraction out of a plane


def view_angles(points, view="auto", order=(0, 1, 2)):
    """(elevation, azimuth) in degrees of the camera for the drawn points (n, 3) (axes order:
    the world axes drawn as x, y, z): "auto" looks along the normal of the plane the points
    span when they spread less than PLANAR of their extent out of it (a planar mechanism seen
    square on), else matplotlib's oblique default (30, -60); "xy", "xz", "yz": along the
    world axis normal to that plane; a pair: as given."""
    if isinstance(view, (tuple, list)) and len(view) == 2:
        return float(view[0]), float(view[1])
    if view not in VIEWS:
        raise ValueError(f"animate: view must be one of {VIEWS} or (elevation, azimuth) in "
                         f"degrees, got {view!r}")
    normal = None
    if view in ("xy", "xz", "yz"):
        axis = ({0, 1, 2} - {"xyz".index(view[0]), "xyz".index(view[1])}).pop()
        normal = np.eye(3)[list(order).index(axis)]
    elif view == "auto" and len(points) >= 3:
        centred = points - points.mean(axis=0)
        _, spread, vt = np.linalg.svd(centred, full_matrices=False)
        if spread[0] > 0.0 and spread[-1] <= PLANAR * spread[0]:
            normal = vt[-1]
    if normal is None:
        return 30.0, -60.0
    if normal[2] < 0 or (normal[2] == 0 and normal[1] > 0):
        normal = -normal                  # seen from above, or from the front
    return (float(np.degrees(np.arcsin(np.clip(normal[2], -1.0, 1.0)))),
            float(np.degrees(np.arctan2(normal[1], normal[0]))))


def _samples(result, pick):
    """The result restricted to the samples pick (what centerlines needs, for the frames
    only)."""
    keep = {name: getattr(result, name)[pick] for name in
            ("t", "rotation", "position_input", "position_mass_center", "position_output")}
    if result.modal_coordinates is not None:
        keep["modal_coordinates"] = result.modal_coordinates[pick]
    return SimpleNamespace(**keep)


def _write_gif(fig, ax, artists, frame, n_frames, fps, path, bar):
    """The frames as a GIF: the figure drawn once without the artists (the axes, the panes,
    the ticks: most of a 3D frame's cost), then per frame that background restored and only
    the artists drawn over it (their 3D projection is the axes' own, fixed); quantized to the
    first frame's palette (Pillow)."""
    from PIL import Image
    canvas = fig.canvas
    for a in artists:
        a.set_visible(False)
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    for a in artists:
        a.set_visible(True)
    images, palette = [], None
    for j in range(n_frames):
        frame(j)
        canvas.restore_region(background)
        for a in artists:
            a.axes.draw_artist(a) if a.axes is not None else fig.draw_artist(a)
        rgb = Image.frombuffer("RGBA", canvas.get_width_height(), canvas.buffer_rgba(),
                               "raw", "RGBA", 0, 1).convert("RGB")
        if palette is None:
            palette = rgb.quantize(colors=255, method=Image.Quantize.MEDIANCUT)
        images.append(rgb.quantize(palette=palette, dither=Image.Dither.NONE))
        bar.update(j + 1)
    images[0].save(path, save_all=True, append_images=images[1:],
                   duration=int(round(1000 / fps)), loop=0)
