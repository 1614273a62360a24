"""Figures as people read them (issue 65, item 9): no panel for a quantity that is zero by
construction, and an animation seen from where the motion shows."""
import subprocess
import sys

import matplotlib
import numpy as np
import pytest

import dttmm
from dttmm.results.plots import animate, view_angles

matplotlib.use("Agg")


def arm(drive=None):
    """Two links on revolute joints about z, the first driven or not, gravity -y."""
    def link(name, **kw):
        return dttmm.RigidBody(mass=1.0, inertia=[1e-3, 1 / 12, 1 / 12],
                               inertia_about="mass_center", to_mass_center=[0.5, 0, 0],
                               to_output=[1.0, 0, 0], name=name, **kw)
    system = dttmm.System(gravity=[0, -9.81, 0])
    system.add(link("upper"), dttmm.RevoluteJoint(axis=[0, 0, 1], drive=drive))
    system.add(link("lower"), dttmm.RevoluteJoint(axis=[0, 0, 1]), parent="upper")
    return system.build()


def test_undriven_joints_draw_no_drive_force():
    """The second joint is undriven (its 'drive force' ~1e-14 N m of rounding was drawn,
    autoscaled): only the driven coordinate is in the force panel; with no drive at all there
    is no force panel."""
    import matplotlib.pyplot as plt
    driven = dttmm.simulate(arm(dttmm.SpringDamper(stiffness=50.0, damping=1.0)), 0.2, 1e-3)
    fig = driven.plot_joints()
    assert len(fig.axes) == 2 and len(fig.axes[1].lines) == 1
    assert len(fig.axes[0].lines) == 2
    free = dttmm.simulate(arm(), 0.2, 1e-3)
    fig2 = free.plot_joints()
    assert len(fig2.axes) == 1
    assert fig.axes[0].get_ylabel() == "coordinate (rad or m)"
    plt.close("all")


def test_a_planar_motion_is_seen_square_on():
    """Points in the world x-y plane, drawn with world y up (gravity -y: drawn axes x, z, y):
    the camera looks along world z, drawn as y (elevation 0, azimuth -90); a spread out of
    the plane gives the oblique default; names and pairs as asked."""
    t = np.linspace(0, 1, 50)
    planar = np.column_stack([np.cos(t), np.zeros_like(t), np.sin(t)])    # drawn (x, z, y)
    assert view_angles(planar, "auto", order=(0, 2, 1)) == pytest.approx((0.0, -90.0))
    spatial = np.column_stack([np.cos(t), np.sin(3 * t), np.sin(t)])
    assert view_angles(spatial, "auto") == (30.0, -60.0)
    assert view_angles(spatial, "xy", order=(0, 2, 1)) == pytest.approx((0.0, -90.0))
    assert view_angles(spatial, (10, 20)) == (10.0, 20.0)
    with pytest.raises(ValueError, match="view must be one of"):
        view_angles(spatial, "sideways")


def test_animation_takes_a_view(tmp_path):
    model = arm()
    result = dttmm.simulate(model, 0.1, 1e-3)
    for view in ("auto", "oblique", (20.0, 45.0)):
        path = animate(result, model, tmp_path / "run.gif", frames=4, view=view, progress=False)
        assert path.stat().st_size > 1000


def test_the_cli_refuses_a_bad_view(tmp_path):
    scene = tmp_path / "three_pendulum.toml"
    subprocess.run([sys.executable, "-m", "dttmm", "example", "three_pendulum", "--to",
                    str(tmp_path)], check=True, capture_output=True)
    out = subprocess.run([sys.executable, "-m", "dttmm", "run", str(scene), "--t-end", "0.01",
                          "--animate", str(tmp_path / "a.gif"), "--view", "sideways"],
                         capture_output=True, text=True)
    assert out.returncode == 2 and "--view sideways" in out.stderr
