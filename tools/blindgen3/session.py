"""Calibration sessions for blindgen3: who moves the rigid body, how, and the room it sits in.

A session is a sequence of holds (the body at rest in one orientation) joined by moves.
World frame: z up. A rotation matrix R maps body-frame vectors to the world frame.
The body carries the sensor at lever arm `lever_m` (body frame, metres) from the point
`pivot` whose path the operator or fixture drives; the sensor's specific force is
R^T (d2/dt2 (pivot + R lever) + g_local e_z).

Session styles (what differs physically):
  table-books   hand-held object set down on a table and propped against books; any
                orientation; moves 1.5-4 s with a lift of 3-15 cm; holds 4-30 s.
  cube-jig      the board screwed in a machined cube, set on its faces (6) and on its
                edges (12, in a V-block), random heading; moves 2-5 s; holds 5-30 s.
  gimbal        motorised two-axis gimbal (outer axis horizontal, inner axis orthogonal),
                trapezoidal velocity moves 90-360 deg/s, sensor 1-6 cm off the axes;
                precise; holds 2-10 s.
  phone-free    phone-style free rotation: the user turns the device along a meandering
                path through the air and rests it on a cushion or against a mug; any
                orientation; moves 1.5-5 s with 10-30 cm travel; holds 2-8 s.
"""

import numpy as np

STYLES = ("table-books", "cube-jig", "gimbal", "phone-free")


# ---------------------------------------------------------------- rotations
def exp_so3(v):
    """Rotation matrices (N,3,3) of rotation vectors v (N,3) in rad (Rodrigues)."""
    v = np.atleast_2d(v)
    th = np.linalg.norm(v, axis=1)
    small = th < 1e-12
    ths = np.where(small, 1.0, th)
    k = v / ths[:, None]
    K = np.zeros((len(v), 3, 3))
    K[:, 0, 1], K[:, 0, 2] = -k[:, 2], k[:, 1]
    K[:, 1, 0], K[:, 1, 2] = k[:, 2], -k[:, 0]
    K[:, 2, 0], K[:, 2, 1] = -k[:, 1], k[:, 0]
    s = np.where(small, 0.0, np.sin(th))[:, None, None]
    c = np.where(small, 0.0, 1 - np.cos(th))[:, None, None]
    R = np.eye(3)[None] + s * K + c * (K @ K)
    # second-order term for tiny angles keeps perturbations exact to O(th^3)
    if small.any():
        vs = v[small]
        Ks = np.zeros((len(vs), 3, 3))
        Ks[:, 0, 1], Ks[:, 0, 2] = -vs[:, 2], vs[:, 1]
        Ks[:, 1, 0], Ks[:, 1, 2] = vs[:, 2], -vs[:, 0]
        Ks[:, 2, 0], Ks[:, 2, 1] = -vs[:, 1], vs[:, 0]
        R[small] = np.eye(3)[None] + Ks + 0.5 * Ks @ Ks
    return R


def log_so3(R):
    """Rotation vector (3,) of one rotation matrix."""
    c = np.clip((np.trace(R) - 1) / 2, -1.0, 1.0)
    th = np.arccos(c)
    if th < 1e-9:
        return np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / 2
    if th > np.pi - 1e-6:
        # near pi: axis from the symmetric part
        A = (R + np.eye(3)) / 2
        i = int(np.argmax(np.diag(A)))
        ax = A[:, i] / np.sqrt(max(A[i, i], 1e-300))
        return ax / np.linalg.norm(ax) * th
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return w * th / (2 * np.sin(th))


def random_rotation(rng):
    """Uniformly distributed rotation (normalised Gaussian quaternion)."""
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def rx_arr(a):
    c, s = np.cos(a), np.sin(a)
    R = np.zeros((len(a), 3, 3))
    R[:, 0, 0] = 1
    R[:, 1, 1], R[:, 1, 2], R[:, 2, 1], R[:, 2, 2] = c, -s, s, c
    return R


def ry_arr(a):
    c, s = np.cos(a), np.sin(a)
    R = np.zeros((len(a), 3, 3))
    R[:, 1, 1] = 1
    R[:, 0, 0], R[:, 0, 2], R[:, 2, 0], R[:, 2, 2] = c, s, -s, c
    return R


def min_jerk(tau):
    """Minimum-jerk position profile 10t^3-15t^4+6t^5 on tau in [0,1]."""
    tau = np.clip(tau, 0, 1)
    return tau ** 3 * (10 - 15 * tau + 6 * tau ** 2)


def trapezoid(tau, T, frac_acc):
    """Trapezoidal-velocity position profile (0..1) on time tau in [0,T], accel phase frac_acc*T."""
    ta = frac_acc * T
    vmax = 1.0 / (T - ta)
    a = vmax / ta
    x = np.where(tau < ta, 0.5 * a * tau ** 2,
                 np.where(tau < T - ta, 0.5 * a * ta ** 2 + vmax * (tau - ta),
                          1 - 0.5 * a * np.clip(T - tau, 0, None) ** 2))
    return np.clip(x, 0, 1)


# ---------------------------------------------------------------- poses and timing
def _cube_orientations():
    """The 6 face and 12 edge orientations of a cube jig: body 'down' directions."""
    downs = []
    for i in range(3):
        for s in (1, -1):
            d = np.zeros(3)
            d[i] = s
            downs.append(d)
    for i in range(3):
        for j in range(i + 1, 3):
            for si in (1, -1):
                for sj in (1, -1):
                    d = np.zeros(3)
                    d[i], d[j] = si, sj
                    downs.append(d / np.sqrt(2))
    return downs


def _rot_taking(u, v):
    """Some rotation taking unit vector u to unit vector v."""
    w = np.cross(u, v)
    s = np.linalg.norm(w)
    c = float(np.dot(u, v))
    if s < 1e-12:
        if c > 0:
            return np.eye(3)
        a = np.array([1.0, 0, 0]) if abs(u[0]) < 0.9 else np.array([0, 1.0, 0])
        ax = np.cross(u, a)
        ax /= np.linalg.norm(ax)
        return exp_so3((ax * np.pi)[None])[0]
    return exp_so3((w / s * np.arctan2(s, c))[None])[0]


def plan(rng, style, n_poses, hold_range=None):
    """Draw the poses (world-from-body rotations), hold and move durations of a session.

    Returns a dict: style, poses [R], holds_s [float], moves_s [float], lever_m (3,),
    and style data (gimbal angles, lift heights, wobble).
    """
    st = dict(style=style)
    if style == "table-books":
        poses = [random_rotation(rng) for _ in range(n_poses)]
        holds = rng.uniform(4, 30, n_poses)
        moves = rng.uniform(1.5, 4, n_poses - 1)
        st["lift_m"] = rng.uniform(0.03, 0.15, n_poses - 1)
        st["travel_m"] = rng.uniform(0.0, 0.2, n_poses - 1)
        st["wobble_rad"] = np.zeros(n_poses - 1)
        lever = rng.uniform(-0.05, 0.05, 3)
    elif style == "cube-jig":
        downs = _cube_orientations()
        faces, edges = list(range(6)), list(range(6, 18))
        rng.shuffle(faces)
        rng.shuffle(edges)
        order = faces + edges
        while len(order) < n_poses:  # repeat faces when more poses than the jig has
            order.append(int(rng.integers(0, 6)))
        order = order[:n_poses]
        poses = []
        for k in order:
            # body 'down' direction must point to world -z; random heading about z
            R = _rot_taking(downs[k], np.array([0, 0, -1.0]))
            poses.append(rz(rng.uniform(0, 2 * np.pi)) @ R)
        holds = rng.uniform(5, 30, n_poses)
        moves = rng.uniform(2, 5, n_poses - 1)
        st["lift_m"] = rng.uniform(0.02, 0.1, n_poses - 1)
        st["travel_m"] = rng.uniform(0.0, 0.1, n_poses - 1)
        st["wobble_rad"] = np.zeros(n_poses - 1)
        lever = rng.uniform(-0.03, 0.03, 3)
    elif style == "gimbal":
        # outer angle a about world x, inner angle b about the rotated y: R = Rx(a) Ry(b)
        if rng.random() < 0.5:
            a = rng.uniform(-np.pi, np.pi, n_poses)
            b = rng.uniform(-np.pi / 2, np.pi / 2, n_poses)
        else:  # a grid scan, shuffled start
            na = int(np.ceil(np.sqrt(n_poses)))
            ga = np.linspace(-np.pi, np.pi, na, endpoint=False) + rng.uniform(0, 0.3)
            gb = np.linspace(-np.pi / 2 * 0.9, np.pi / 2 * 0.9, int(np.ceil(n_poses / na)))
            A, B = np.meshgrid(ga, gb)
            a, b = A.ravel()[:n_poses], B.ravel()[:n_poses]
        st["a"], st["b"] = a, b
        poses = [rx_arr(np.array([ai]))[0] @ ry_arr(np.array([bi]))[0] for ai, bi in zip(a, b)]
        st["vmax"] = np.radians(rng.uniform(90, 360))
        st["frac_acc"] = rng.uniform(0.15, 0.4)
        d = np.maximum(np.abs(np.diff(a)), np.abs(np.diff(b)))
        moves = np.maximum(0.2, d / st["vmax"] / (1 - st["frac_acc"]))
        holds = rng.uniform(2, 10, n_poses)
        lever = rng.uniform(0.01, 0.06, 3) * rng.choice([-1, 1], 3)
    elif style == "phone-free":
        poses = [random_rotation(rng) for _ in range(n_poses)]
        holds = rng.uniform(2, 8, n_poses)
        moves = rng.uniform(1.5, 5, n_poses - 1)
        st["lift_m"] = rng.uniform(0.1, 0.3, n_poses - 1)
        st["travel_m"] = rng.uniform(0.0, 0.3, n_poses - 1)
        st["wobble_rad"] = rng.uniform(0.2, 1.0, n_poses - 1)
        lever = rng.uniform(-0.06, 0.06, 3)
    else:
        raise ValueError(style)
    if hold_range is not None:
        holds = rng.uniform(hold_range[0], hold_range[1], n_poses)
    st.update(poses=poses, holds_s=np.asarray(holds, float), moves_s=np.asarray(moves, float),
              lever_m=lever)
    return st


def fit_budget(st, odr, max_rows):
    """Shorten holds (not below 2 s) so the session holds at most max_rows samples at odr."""
    total = st["holds_s"].sum() + st["moves_s"].sum()
    budget = max_rows / odr
    if total > budget:
        room = budget - st["moves_s"].sum() - 1.0
        f = room / st["holds_s"].sum()
        st["holds_s"] = np.maximum(2.0, st["holds_s"] * f)
    return st


def timeline(st):
    """Segments [(kind, t0, t1, index)] with kind 'hold' (index = pose) or 'move' (index = move)."""
    segs, t = [], 0.0
    n = len(st["poses"])
    for i in range(n):
        segs.append(("hold", t, t + st["holds_s"][i], i))
        t += st["holds_s"][i]
        if i < n - 1:
            segs.append(("move", t, t + st["moves_s"][i], i))
            t += st["moves_s"][i]
    return segs, t


def trajectory(st, t, segs, rng):
    """World-from-body rotations R (N,3,3) and pivot positions (N,3), metres, on time grid t."""
    N = len(t)
    R = np.empty((N, 3, 3))
    P = np.zeros((N, 3))
    poses = st["poses"]
    pos = np.zeros((len(poses), 3))  # resting place of each pose on the table
    for i in range(1, len(poses)):
        if st["style"] == "gimbal":
            continue
        ang = rng.uniform(0, 2 * np.pi)
        pos[i] = pos[i - 1] + st["travel_m"][i - 1] * np.array([np.cos(ang), np.sin(ang), 0])
    for kind, t0, t1, k in segs:
        m = (t >= t0) & (t < t1) if t1 < t[-1] + 1e-9 else (t >= t0)
        if not m.any():
            continue
        if kind == "hold":
            R[m] = poses[k]
            P[m] = pos[k]
            continue
        tau = (t[m] - t0) / (t1 - t0)
        Ra, Rb = poses[k], poses[k + 1]
        if st["style"] == "gimbal":
            x = trapezoid(t[m] - t0, t1 - t0, st["frac_acc"])
            a = st["a"][k] + (st["a"][k + 1] - st["a"][k]) * x
            b = st["b"][k] + (st["b"][k + 1] - st["b"][k]) * x
            R[m] = rx_arr(a) @ ry_arr(b)
            P[m] = 0.0
            continue
        s = min_jerk(tau)
        phi = log_so3(Ra.T @ Rb)
        Rm = Ra[None] @ exp_so3(s[:, None] * phi[None])
        w = st["wobble_rad"][k]
        if w > 0:  # meandering path: a rotation bump about a random body axis, zero at both ends
            u = rng.normal(size=3)
            u /= np.linalg.norm(u)
            Rm = Rm @ exp_so3((np.sin(np.pi * s) * w)[:, None] * u[None])
        R[m] = Rm
        P[m] = pos[k] + (pos[k + 1] - pos[k]) * s[:, None]
        P[m, 2] += st["lift_m"][k] * np.sin(np.pi * s) ** 2
    return R, P


# ---------------------------------------------------------------- room and die temperature
def temperature(rng, t, segs, ds, scenario="ordinary", hand=True):
    """Die temperature (degC) on grid t and the scenario's parameters.

    ordinary:      room T0 18-28 degC drifting +-1 K/h, HVAC ripple 0-0.3 K (period 10-30 min);
                   die self-heating dT 'self_heat_k' of the part with tau 60-600 s, powered up
                   0-1200 s before the log starts; each hand move warms the body by 0-0.05 K
                   (decays with tau 60 s; not on the gimbal: hand=False).
    warmed-up:     as ordinary, powered up 30-120 min before the log (flat die temperature).
    power-up:      log starts at power-up; board self-heating (MCU, radio, regulator) 2-8 K,
                   tau 60-400 s, on top of the part's own.
    from-cold:     board taken out of a fridge: starts 6-15 K below the room and warms with
                   tau 150-600 s (first-order).
    chamber-ramp:  climatic chamber: linear ramp 0.3-1.5 K/min from the room, sometimes
                   up then down (triangle).
    """
    p = dict(scenario=scenario)
    T0 = rng.uniform(18, 28)
    rate = rng.uniform(-1, 1) / 3600
    amp = rng.uniform(0, 0.3)
    per = rng.uniform(600, 1800)
    room = T0 + rate * t + amp * np.sin(2 * np.pi * t / per + rng.uniform(0, 2 * np.pi))
    dsh = rng.uniform(*ds["self_heat_k"])
    tau = rng.uniform(60, 600)
    t_on = rng.uniform(0, 1200)
    if scenario == "warmed-up":
        t_on = rng.uniform(1800, 7200)
    if scenario == "power-up":
        t_on = 0.0
        dsh += rng.uniform(2, 8)
        tau = rng.uniform(60, 400)
    T = room + dsh * (1 - np.exp(-(t + t_on) / tau))
    if scenario == "from-cold":
        dT = rng.uniform(6, 15)
        tc = rng.uniform(150, 600)
        T = T - dT * np.exp(-t / tc)
        p.update(cold_k=dT, tau_cold_s=tc)
    if scenario == "chamber-ramp":
        r = rng.uniform(0.3, 1.5) / 60
        if rng.random() < 0.4:
            tm = t[-1] / 2
            T = T + r * np.where(t < tm, t, 2 * tm - t)
        else:
            T = T + r * t
        p.update(ramp_k_per_s=r)
    # hand warmth: each hand move adds a small step that decays
    for kind, t0, t1, k in segs:
        if kind == "move" and hand:
            d = rng.uniform(0, 0.05)
            m = t >= t1
            T[m] += d * np.exp(-(t[m] - t1) / 60.0)
    p.update(room0_c=T0, self_heat_k=dsh, self_heat_tau_s=tau, t_on_s=t_on, span_k=float(T.max() - T.min()))
    return T, p
