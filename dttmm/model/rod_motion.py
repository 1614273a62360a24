"""A strain rod's motion evaluated in Python from its parameter row and coordinates
(docs/strain_rod.md): its end section and output point, its centre line, its energies and its
small-vibration frequencies, through the kernels' kinematics (kernels/transfers/strain_rod.py).
Above the kernels: the element (elements/strain_rod.py) only declares the rod and its tables."""
import numpy as np

from ..elements.strain_rod import (ROD_LENGTH, ROD_MODES, ROD_MU, kinematics_tables, rod_components,
                                   rod_coordinate_count, rod_section, rod_stiffness, rod_tables)
from ..kernels.transfers.strain_rod import (rod_end_points, rod_jacobians, rod_kinematics,
                                            station_arrays)


def rod_end_section(row, rotation, omega, q, q_dot=None):
    """(r_O - r_I, A_O, w_O) of a rod in a given state: its end point and end section (world)
    from its frame (rotation A, world angular velocity w) and strain coordinates."""
    steps, xi0, phi, _ = rod_tables(row)
    n = len(steps) + 1
    rot, pos, om, vel, al, acc = station_arrays(n)
    # writable copies: numba types read-only arrays apart (a Result's coordinates compiled the
    # kernel a second time, ~5 s)
    q = np.array(q, dtype=float)
    q_dot = np.zeros_like(q) if q_dot is None else np.array(q_dot, dtype=float)
    rod_kinematics(steps, xi0, phi, q, q_dot, np.zeros_like(q), rot, pos, om, vel, al, acc)
    return rotation @ pos[-1], rotation @ rot[-1], omega + rotation @ om[-1]


def rod_frequencies(row):
    """(n_q,) Hz: the rod's own frequencies clamped at its input, straight and at rest: the
    eigenvalues of K against the mass matrix of its strain coordinates there, M = sum_i w_i
    (mu Jp_i^T Jp_i + Jr_i^T diag(section) Jr_i) (its stations' Jacobians, rod_jacobians;
    describe()'s step)."""
    steps, xi0, phi, weights = rod_tables(row)
    nq = rod_coordinate_count(row)
    jp, jr = rod_jacobians(steps, xi0, phi, np.zeros(nq))
    section = rod_section(row)
    mass = (row[ROD_MU] * np.einsum("i,ija,ika->jk", weights, jp, jp)
            + np.einsum("i,ija,a,ika->jk", weights, jr, section, jr))
    squared = np.linalg.eigvals(np.linalg.solve(mass, np.diag(rod_stiffness(row)))).real
    return np.sqrt(np.sort(np.maximum(squared, 0.0))) / (2.0 * np.pi)


def rod_output_offset(row, rotation, omega, q, q_dot):
    """(rho, rho') (T, 3): a rod's output point relative to its input point and its velocity
    relative to the input point's, world, for T states of its frame (rotation (T, 3, 3), world
    angular velocity (T, 3)) and strain coordinates and rates (T, n_q): rho = A p_L,
    rho' = w x rho + A p_L' (rod_kinematics' last station)."""
    steps, xi0, phi, _ = rod_tables(row)
    q = np.array(q, dtype=float).reshape(-1, phi.shape[-1])         # (writable copies, as
    q_dot = np.array(q_dot, dtype=float).reshape(q.shape)           # rod_end_section)
    p_end, v_end = rod_end_points(steps, xi0, phi, q, q_dot)
    rotation = np.asarray(rotation, dtype=float).reshape(-1, 3, 3)
    rho = np.einsum("tij,tj->ti", rotation, p_end)
    rho_dot = (np.cross(np.asarray(omega, dtype=float).reshape(-1, 3), rho)
               + np.einsum("tij,tj->ti", rotation, v_end))
    return rho, rho_dot


def rod_centre_line(row, q, points):
    """(T, points, 3) points equally spaced along a rod's centre line in its frame, for its
    strain coordinates q (T, n_q): the Magnus steps between them (docs/strain_rod.md), for
    drawing (the rod's own stations give its end: the last point differs from it by the
    steps' error, ~h^5 per step of a varying strain, nothing for a constant one)."""
    length = row[ROD_LENGTH]
    x = np.linspace(0.0, length, points)[1:]
    steps, xi0, phi = kinematics_tables(length, x, int(row[ROD_MODES]), rod_components(row))
    n = points
    rot, pos, om, vel, al, acc = station_arrays(n)
    out = np.zeros((len(q), points, 3))
    for t in range(len(q)):
        qt = np.array(q[t], dtype=float)        # (a writable copy, as rod_end_section)
        zero = np.zeros_like(qt)
        rod_kinematics(steps, xi0, phi, qt, zero, zero, rot, pos, om, vel, al, acc)
        out[t] = pos
    return out


def rod_energies(row, rotation, omega, r_in, v_in, q, q_dot, gravity):
    """(kinetic, potential) (T,) of a rod over T states: sum over its stations of
    1/2 f |v_i|^2 + 1/2 W_i . Theta_i W_i (f = mu w_i, Theta_i = w_i R_i diag(j_p, rho I_w,
    rho I_v) R_i^T, W_i the section's world angular velocity) and -f g . r_i, plus the strain
    energy 1/2 q^T K q (docs/strain_rod.md)."""
    steps, xi0, phi, weights = rod_tables(row)
    n = len(steps) + 1
    section = np.diag(rod_section(row))
    stiffness = rod_stiffness(row)
    kinetic, potential = np.zeros(len(q)), np.zeros(len(q))
    rot, pos, om, vel, al, acc = station_arrays(n)
    for t in range(len(q)):
        qt, qdt = np.array(q[t], dtype=float), np.array(q_dot[t], dtype=float)   # (writable)
        rod_kinematics(steps, xi0, phi, qt, qdt, np.zeros_like(qt), rot, pos, om, vel, al, acc)
        a, w = rotation[t], omega[t]
        rho = pos @ a.T                                         # (stations, 3) world
        v = v_in[t] + np.cross(w, rho) + vel @ a.T
        big_w = w + om @ a.T
        theta = np.einsum("i,kab,bc,kdc->kad", weights, rot, section, rot)   # section frame
        w_sec = np.einsum("ab,kb->ka", a.T, big_w)                           # in the frame
        kinetic[t] = 0.5 * row[ROD_MU] * np.einsum("k,ki,ki->", weights, v, v) \
            + 0.5 * np.einsum("ka,kab,kb->", w_sec, theta, w_sec)
        potential[t] = (-row[ROD_MU] * weights @ ((r_in[t] + rho) @ gravity)
                        + 0.5 * qt @ (stiffness * qt))
    return kinetic, potential
