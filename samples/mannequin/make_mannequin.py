#!/usr/bin/env python3
"""Generate drape's built-in sample character: a rigged, skinned, animated
humanoid mannequin written as a single self-contained glTF 2.0 file.

    python3 samples/mannequin/make_mannequin.py samples/mannequin/mannequin.gltf

Only the Python standard library is used, and the output is deterministic
(byte-identical on every run): no clocks, no randomness, fixed rounding.

Conventions: metres, +Y up, the character faces +Z, its left is +X.
Rest pose == bind pose (A-pose, arms 40 degrees below horizontal).
"""

import base64
import json
import math
import struct
import sys

# --------------------------------------------------------------------------
# Small math helpers (quaternions are (x, y, z, w), glTF order)
# --------------------------------------------------------------------------


def v_add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def v_sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def v_scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def v_dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def v_cross(a, b):
    return (a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0])


def v_norm(a):
    n = math.sqrt(v_dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def q_axis_angle(axis, deg):
    axis = v_norm(axis)
    h = math.radians(deg) * 0.5
    s = math.sin(h)
    return (axis[0] * s, axis[1] * s, axis[2] * s, math.cos(h))


def q_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def q_conj(q):
    return (-q[0], -q[1], -q[2], q[3])


def q_rotate(q, v):
    p = q_mul(q_mul(q, (v[0], v[1], v[2], 0.0)), q_conj(q))
    return (p[0], p[1], p[2])


def q_canon(q):
    """Unit length, w >= 0 (keeps animation keys on one hemisphere)."""
    n = math.sqrt(sum(c * c for c in q))
    q = tuple(c / n for c in q)
    if q[3] < 0.0:
        q = tuple(-c for c in q)
    return q


def m4_from_trs(t, q):
    """Row-major 4x4 from translation + (not re-normalised) quaternion."""
    x, y, z, w = q
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w), t[0]],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w), t[1]],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y), t[2]],
        [0.0, 0.0, 0.0, 1.0],
    ]


def m4_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)]
            for i in range(4)]


def m4_inverse(m):
    """General 4x4 inverse (Gauss-Jordan with partial pivoting)."""
    a = [list(m[i]) + [1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]
    for c in range(4):
        p = max(range(c, 4), key=lambda r: abs(a[r][c]))
        a[c], a[p] = a[p], a[c]
        pv = a[c][c]
        a[c] = [v / pv for v in a[c]]
        for r in range(4):
            if r != c and a[r][c] != 0.0:
                f = a[r][c]
                a[r] = [a[r][k] - f * a[c][k] for k in range(8)]
    return [row[4:] for row in a]


def rnd(x, nd=7):
    """Fixed rounding for numbers written into the JSON (no -0.0)."""
    return round(x, nd) + 0.0


def f32(x):
    return struct.unpack('<f', struct.pack('<f', x))[0]


def smoothstep(t):
    t = min(1.0, max(0.0, t))
    return t * t * (3.0 - 2.0 * t)


def lerp_keys(keys, s):
    """Piecewise-linear interpolation of tuples keyed by keys[i][0]."""
    if s <= keys[0][0]:
        return keys[0][1:]
    for k0, k1 in zip(keys, keys[1:]):
        if s <= k1[0]:
            t = (s - k0[0]) / (k1[0] - k0[0])
            return tuple(a + (b - a) * t for a, b in zip(k0[1:], k1[1:]))
    return keys[-1][1:]


# --------------------------------------------------------------------------
# Skeleton (rest == bind pose), global positions and rotations
# --------------------------------------------------------------------------

ARM_DROP_DEG = 40.0          # A-pose: arms 40 degrees below horizontal
UPPER_ARM, FOREARM, HAND = 0.28, 0.25, 0.17
THIGH, SHIN = 0.42, 0.40
SHOULDER_X, SHOULDER_Y = 0.19, 1.42
HIP_X, HIP_Y = 0.095, 0.90

_c, _s = math.cos(math.radians(ARM_DROP_DEG)), math.sin(math.radians(ARM_DROP_DEG))
ARM_DIR = {'l': (_c, -_s, 0.0), 'r': (-_c, -_s, 0.0)}
# Arm joints get a rest rotation so that their local +Y runs along the bone
# (toward the hand) and local +X is the elbow flexion axis: a positive
# rotation about local X swings the bone toward +Z (forward).
ARM_ROT = {'l': q_axis_angle((0, 0, 1), -(90.0 + ARM_DROP_DEG)),
           'r': q_axis_angle((0, 0, 1), +(90.0 + ARM_DROP_DEG))}
IDENT = (0.0, 0.0, 0.0, 1.0)


def _arm_joints(side):
    d = ARM_DIR[side]
    sx = SHOULDER_X if side == 'l' else -SHOULDER_X
    sh = (sx, SHOULDER_Y, 0.0)
    el = v_add(sh, v_scale(d, UPPER_ARM))
    wr = v_add(el, v_scale(d, FOREARM))
    r = ARM_ROT[side]
    return [('shoulder_' + side, 'chest', sh, r),
            ('elbow_' + side, 'shoulder_' + side, el, r),
            ('wrist_' + side, 'elbow_' + side, wr, r)]


def _leg_joints(side):
    x = HIP_X if side == 'l' else -HIP_X
    return [('hip_' + side, 'hips', (x, HIP_Y, 0.0), IDENT),
            ('knee_' + side, 'hip_' + side, (x, HIP_Y - THIGH, 0.0), IDENT),
            ('ankle_' + side, 'knee_' + side, (x, HIP_Y - THIGH - SHIN, 0.0), IDENT)]


# (name, parent, global position, global rotation); parents before children
JOINTS = ([('hips', None, (0.0, 0.95, 0.0), IDENT),
           ('spine', 'hips', (0.0, 1.05, 0.0), IDENT),
           ('chest', 'spine', (0.0, 1.22, 0.0), IDENT),
           ('neck', 'chest', (0.0, 1.44, 0.0), IDENT),
           ('head', 'neck', (0.0, 1.56, 0.0), IDENT)]
          + _arm_joints('l') + _arm_joints('r')
          + _leg_joints('l') + _leg_joints('r'))
JOINT_NAMES = [j[0] for j in JOINTS]
JOINT_INDEX = {n: i for i, n in enumerate(JOINT_NAMES)}
JOINT_GLOBAL = {j[0]: (j[2], j[3]) for j in JOINTS}
JOINT_PARENT = {j[0]: j[1] for j in JOINTS}


def local_rest(name):
    """Local translation and rotation, rounded as written to the file."""
    pos, rot = JOINT_GLOBAL[name]
    parent = JOINT_PARENT[name]
    if parent is None:
        t, q = pos, rot
    else:
        ppos, prot = JOINT_GLOBAL[parent]
        t = q_rotate(q_conj(prot), v_sub(pos, ppos))
        q = q_mul(q_conj(prot), rot)
    q = q_canon(q)
    return tuple(rnd(c) for c in t), tuple(rnd(c) for c in q)


LOCAL_REST = {n: local_rest(n) for n in JOINT_NAMES}


def global_rest_matrices():
    """Global rest matrices built from the *written* local TRS values."""
    g = {}
    for name in JOINT_NAMES:
        t, q = LOCAL_REST[name]
        m = m4_from_trs(t, q)
        parent = JOINT_PARENT[name]
        g[name] = m if parent is None else m4_mul(g[parent], m)
    return g


# --------------------------------------------------------------------------
# Mesh: closed generalized cylinders swept along straight axes
# --------------------------------------------------------------------------

SEGMENTS = 24                      # around torso, head and legs
LIMB_SEGMENTS = 20                 # around the thinner arms
SMALL_SEGMENTS = 16                # around neck and feet
# ring spacing along the axis: dense within DENSE_HALF of a joint, else sparse
DENSE_STEP, SPARSE_STEP, DENSE_HALF = 0.025, 0.05, 0.05


class Part:
    """A closed tube along origin + s*axis, s in [s0, s1], with rounded caps.

    profile(s) -> (centre offset vector, radius along u, radius along v).
    Cross-sections are superellipses with exponent `exponent` (2 = ellipse).
    chain: [(s_joint, joint_name, blend_half_width)], first_bone: bone used
    before the first joint.  Weights depend only on the ring's s.
    """

    def __init__(self, name, origin, axis, u, s0, s1, profile, cap0, cap1,
                 first_bone, chain, exponent=2.0, cap_rings=3, segments=SEGMENTS):
        self.name = name
        self.origin = origin
        self.axis = v_norm(axis)
        self.u = v_norm(u)
        self.v = v_cross(self.axis, self.u)   # (u, v, axis) right-handed
        self.s0, self.s1 = s0, s1
        self.profile = profile
        self.cap0, self.cap1 = cap0, cap1
        self.first_bone = first_bone
        self.chain = chain
        self.exponent = exponent
        self.cap_rings = cap_rings
        self.segments = segments

    # ring positions: list of (s, radius factor)
    def rings(self):
        a, b = self.s0 + self.cap0, self.s1 - self.cap1
        out = []
        k = self.cap_rings
        for i in range(1, k):
            th = 0.5 * math.pi * i / k
            out.append((self.s0 + self.cap0 * (1.0 - math.cos(th)), math.sin(th)))
        if b - a < 1e-9:
            out.append((a, 1.0))
        else:
            cuts = {a, b}
            for sj, _, _ in self.chain:
                for c in (sj - DENSE_HALF, sj + DENSE_HALF):
                    if a < c < b:
                        cuts.add(c)
            cuts = sorted(cuts)
            body = [a]
            for c0, c1 in zip(cuts, cuts[1:]):
                mid = 0.5 * (c0 + c1)
                dense = any(abs(mid - sj) < DENSE_HALF for sj, _, _ in self.chain)
                step = DENSE_STEP if dense else SPARSE_STEP
                n = max(1, int(math.ceil((c1 - c0) / step - 1e-9)))
                body.extend(c0 + (c1 - c0) * i / n for i in range(1, n + 1))
            out.extend((s, 1.0) for s in body)
        for i in range(k - 1, 0, -1):
            th = 0.5 * math.pi * i / k
            out.append((self.s1 - self.cap1 * (1.0 - math.cos(th)), math.sin(th)))
        return out

    def weights(self, s):
        bone = self.first_bone
        for sj, joint, _ in self.chain:
            if s >= sj:
                bone = joint
        w = {bone: 1.0}
        parent = self.first_bone
        for sj, joint, half in self.chain:
            if abs(s - sj) < half:
                wc = smoothstep((s - (sj - half)) / (2.0 * half))
                w = {}
                if 1.0 - wc > 0.0:
                    w[parent] = 1.0 - wc
                if wc > 0.0:
                    w[joint] = wc
            parent = joint
        return w

    def point(self, s, fac, phi):
        off, ra, rb = self.profile(s)
        c, sn = math.cos(phi), math.sin(phi)
        e = 2.0 / self.exponent
        c = math.copysign(abs(c) ** e, c)
        sn = math.copysign(abs(sn) ** e, sn)
        p = v_add(self.origin, v_add(off, v_scale(self.axis, s)))
        p = v_add(p, v_scale(self.u, ra * fac * c))
        return v_add(p, v_scale(self.v, rb * fac * sn))

    def build(self):
        """Return (positions, s-values, triangles) with local indices."""
        n = self.segments
        rings = self.rings()
        pos, svals, tris = [], [], []
        pos.append(v_add(self.origin, v_add(self.profile(self.s0)[0],
                                            v_scale(self.axis, self.s0))))
        svals.append(self.s0)
        for s, fac in rings:
            for j in range(n):
                pos.append(self.point(s, fac, 2.0 * math.pi * j / n))
                svals.append(s)
        pos.append(v_add(self.origin, v_add(self.profile(self.s1)[0],
                                            v_scale(self.axis, self.s1))))
        svals.append(self.s1)
        last = len(pos) - 1

        def rv(r, j):
            return 1 + r * n + (j % n)

        for j in range(n):                       # start cap fan
            tris.append((0, rv(0, j + 1), rv(0, j)))
        for r in range(len(rings) - 1):          # bands
            for j in range(n):
                a, b = rv(r, j), rv(r, j + 1)
                c, d = rv(r + 1, j + 1), rv(r + 1, j)
                tris.append((a, b, c))
                tris.append((a, c, d))
        rl = len(rings) - 1
        for j in range(n):                       # end cap fan
            tris.append((rv(rl, j), rv(rl, j + 1), last))
        return pos, svals, tris


def _const(a, b=None, off=(0.0, 0.0, 0.0)):
    b = a if b is None else b
    return lambda s: (off, a, b)


def _keyed(keys, off=(0.0, 0.0, 0.0)):
    def f(s):
        a, b = lerp_keys(keys, s)
        return off, a, b
    return f


def make_parts():
    parts = []
    # Torso: along +Y, s = height; elliptical, tapering waist.
    torso_keys = [(0.82, 0.120, 0.090), (0.88, 0.150, 0.100),
                  (0.95, 0.165, 0.110), (1.05, 0.140, 0.095),
                  (1.12, 0.145, 0.100), (1.25, 0.165, 0.110),
                  (1.38, 0.170, 0.100), (1.48, 0.160, 0.090)]
    parts.append(Part('torso', (0, 0, 0), (0, 1, 0), (1, 0, 0), 0.82, 1.48,
                      _keyed(torso_keys), 0.06, 0.07, 'hips',
                      [(1.05, 'spine', 0.05), (1.22, 'chest', 0.05)]))
    # Neck: into the torso below and into the head above.
    parts.append(Part('neck', (0, 0, 0), (0, 1, 0), (1, 0, 0), 1.38, 1.62,
                      _keyed([(1.38, 0.055, 0.055), (1.50, 0.050, 0.050),
                              (1.62, 0.048, 0.048)]), 0.02, 0.02, 'chest',
                      [(1.44, 'neck', 0.04), (1.56, 'head', 0.04)],
                      segments=SMALL_SEGMENTS))
    # Head: ellipsoid, half-axes 0.10 (x) x 0.12 (y) x 0.11 (z), top at 1.75.
    parts.append(Part('head', (0, 0, 0), (0, 1, 0), (1, 0, 0), 1.51, 1.75,
                      _const(0.10, 0.11), 0.12, 0.12, 'head', [],
                      cap_rings=7))
    arm_keys = [(-0.07, 0.050, 0.050), (0.00, 0.050, 0.050),
                (0.10, 0.047, 0.047), (0.28, 0.036, 0.036),
                (0.40, 0.035, 0.035), (0.53, 0.027, 0.027),
                (0.57, 0.040, 0.020), (0.66, 0.045, 0.019),
                (0.70, 0.040, 0.017)]
    leg_keys = [(-0.08, 0.075, 0.075), (0.00, 0.080, 0.080),
                (0.08, 0.078, 0.078), (0.25, 0.068, 0.068),
                (0.42, 0.052, 0.052), (0.50, 0.055, 0.055),
                (0.55, 0.057, 0.057), (0.70, 0.045, 0.045),
                (0.80, 0.040, 0.040), (0.85, 0.038, 0.038)]
    foot_keys = [(-0.065, 0.038, 0.040), (-0.03, 0.042, 0.045),
                 (0.03, 0.044, 0.043), (0.10, 0.046, 0.033),
                 (0.15, 0.045, 0.026), (0.19, 0.040, 0.020)]
    for side in ('l', 'r'):
        sh = JOINT_GLOBAL['shoulder_' + side][0]
        # Hand is flat in the plane of the arm and +Z: wide along u = +Z.
        parts.append(Part('arm_' + side, sh, ARM_DIR[side], (0, 0, 1),
                          -0.07, 0.70, _keyed(arm_keys), 0.03, 0.03,
                          'chest',
                          [(0.0, 'shoulder_' + side, 0.05),
                           (UPPER_ARM, 'elbow_' + side, 0.05),
                           (UPPER_ARM + FOREARM, 'wrist_' + side, 0.04)],
                          segments=LIMB_SEGMENTS))
        hip = JOINT_GLOBAL['hip_' + side][0]
        parts.append(Part('leg_' + side, hip, (0, -1, 0), (1, 0, 0),
                          -0.08, 0.85, _keyed(leg_keys), 0.04, 0.02, 'hips',
                          [(0.0, 'hip_' + side, 0.05),
                           (THIGH, 'knee_' + side, 0.05),
                           (THIGH + SHIN, 'ankle_' + side, 0.04)]))
        fx = hip[0]

        def foot_profile(s, fx=fx):
            a, h = lerp_keys(foot_keys, s)
            return (fx, h, 0.0), a, h    # centre at height h: sole at y = 0

        parts.append(Part('foot_' + side, (0, 0, 0), (0, 0, 1), (1, 0, 0),
                          -0.065, 0.19, foot_profile, 0.025, 0.025,
                          'ankle_' + side, [], exponent=3.5,
                          segments=SMALL_SEGMENTS))
    return parts


def build_mesh():
    positions, normals, joints, weights, indices = [], [], [], [], []
    part_ranges = []
    for part in make_parts():
        pos, svals, tris = part.build()
        base = len(positions)
        acc = [(0.0, 0.0, 0.0)] * len(pos)
        for a, b, c in tris:
            fn = v_cross(v_sub(pos[b], pos[a]), v_sub(pos[c], pos[a]))
            for i in (a, b, c):
                acc[i] = v_add(acc[i], fn)
        for p, nrm, s in zip(pos, acc, svals):
            positions.append(p)
            normals.append(v_norm(nrm))
            w = sorted(part.weights(s).items(), key=lambda kv: (-kv[1], JOINT_INDEX[kv[0]]))
            jj = [JOINT_INDEX[k] for k, _ in w] + [0] * (4 - len(w))
            ww = [x for _, x in w] + [0.0] * (4 - len(w))
            joints.append(jj)
            weights.append(ww)
        t0 = len(indices)
        indices.extend((a + base, b + base, c + base) for a, b, c in tris)
        part_ranges.append((part.name, base, len(positions) - base, t0, len(tris)))
    return positions, normals, joints, weights, indices, part_ranges


# --------------------------------------------------------------------------
# Animation: in-place walk, 1 s loop, 31 keys, LINEAR
# --------------------------------------------------------------------------

FPS, DURATION = 30, 1.0
NKEYS = FPS + 1


def walk_pose(t):
    """Joint -> delta rotation (quaternion in the joint's local frame, applied
    after the rest rotation) and the hips translation, at time t in [0, 1)."""
    p = 2.0 * math.pi * t
    X, Y = (1, 0, 0), (0, 1, 0)
    d = {}
    # Legs (identity rest frames): negative about X swings the leg forward,
    # positive about X at the knee is flexion.
    for side, ph in (('l', 0.0), ('r', math.pi)):
        thigh = -25.0 * math.sin(p + ph)
        knee = 50.0 * ((1.0 + math.cos(p + ph + 0.4)) * 0.5) ** 2
        ankle = max(-20.0, min(20.0, -0.4 * (thigh + knee)))
        d['hip_' + side] = q_axis_angle(X, thigh)
        d['knee_' + side] = q_axis_angle(X, knee)
        d['ankle_' + side] = q_axis_angle(X, ankle)
    # Arms (local X = flexion axis, positive = forward), opposite the legs.
    for side, ph in (('l', 0.0), ('r', math.pi)):
        d['shoulder_' + side] = q_axis_angle(X, -20.0 * math.sin(p + ph))
        d['elbow_' + side] = q_axis_angle(X, 20.0 - 10.0 * math.sin(p + ph))
    # Pelvis yaws with the swinging leg; spine and chest counter-rotate,
    # the neck keeps the head looking ahead.
    d['hips'] = q_axis_angle(Y, -4.0 * math.sin(p))
    d['spine'] = q_axis_angle(Y, 3.0 * math.sin(p))
    d['chest'] = q_axis_angle(Y, 3.0 * math.sin(p))
    d['neck'] = q_axis_angle(Y, -2.0 * math.sin(p))
    hips_t = LOCAL_REST['hips'][0]
    trans = (hips_t[0] - 0.015 * math.cos(p),
             hips_t[1] - 0.02 * 0.5 * (1.0 - math.cos(2.0 * p)),
             hips_t[2])
    return d, trans


ANIMATED = ['hips', 'spine', 'chest', 'neck',
            'shoulder_l', 'elbow_l', 'shoulder_r', 'elbow_r',
            'hip_l', 'knee_l', 'ankle_l', 'hip_r', 'knee_r', 'ankle_r']


def build_animation():
    times = [f32(k / FPS) for k in range(NKEYS)]
    rot = {n: [] for n in ANIMATED}
    trans = []
    for k in range(NKEYS - 1):
        delta, tr = walk_pose(k / FPS)
        for n in ANIMATED:
            q = q_canon(q_mul(LOCAL_REST[n][1], delta[n]))
            rot[n].append(tuple(f32(c) for c in q))
        trans.append(tuple(f32(c) for c in tr))
    for n in ANIMATED:                        # seamless loop: last == first
        rot[n].append(rot[n][0])
    trans.append(trans[0])
    return times, rot, trans


# --------------------------------------------------------------------------
# glTF assembly
# --------------------------------------------------------------------------


class Blob:
    def __init__(self):
        self.data = bytearray()
        self.views = []
        self.accessors = []

    def add(self, raw, target=None):
        while len(self.data) % 4:
            self.data.append(0)
        view = {'buffer': 0, 'byteOffset': len(self.data), 'byteLength': len(raw)}
        if target is not None:
            view['target'] = target
        self.data.extend(raw)
        self.views.append(view)
        return len(self.views) - 1

    def accessor(self, raw, ctype, count, atype, target=None, mn=None, mx=None):
        acc = {'bufferView': self.add(raw, target), 'byteOffset': 0,
               'componentType': ctype, 'count': count, 'type': atype}
        if mn is not None:
            acc['min'] = mn
            acc['max'] = mx
        self.accessors.append(acc)
        return len(self.accessors) - 1


FLOAT, USHORT, UINT = 5126, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


def pack_f(vals):
    return struct.pack('<%df' % len(vals), *vals)


def build_gltf():
    positions, normals, joints, weights, indices, _ = build_mesh()
    nv = len(positions)
    blob = Blob()

    flat_pos = [f32(c) for p in positions for c in p]
    pmin = [min(flat_pos[i::3]) for i in range(3)]
    pmax = [max(flat_pos[i::3]) for i in range(3)]
    a_pos = blob.accessor(pack_f(flat_pos), FLOAT, nv, 'VEC3', ARRAY_BUFFER, pmin, pmax)
    a_nrm = blob.accessor(pack_f([c for n in normals for c in n]), FLOAT, nv,
                          'VEC3', ARRAY_BUFFER)
    a_jnt = blob.accessor(struct.pack('<%dH' % (4 * nv), *[j for jj in joints for j in jj]),
                          USHORT, nv, 'VEC4', ARRAY_BUFFER)
    a_wgt = blob.accessor(pack_f([w for ww in weights for w in ww]), FLOAT, nv,
                          'VEC4', ARRAY_BUFFER)
    flat_idx = [i for tri in indices for i in tri]
    a_idx = blob.accessor(struct.pack('<%dI' % len(flat_idx), *flat_idx), UINT,
                          len(flat_idx), 'SCALAR', ELEMENT_ARRAY_BUFFER)

    g = global_rest_matrices()
    ibm = []
    for name in JOINT_NAMES:
        inv = m4_inverse(g[name])
        ibm.extend(inv[r][c] for c in range(4) for r in range(4))   # column-major
    a_ibm = blob.accessor(pack_f(ibm), FLOAT, len(JOINT_NAMES), 'MAT4')

    times, rot, trans = build_animation()
    a_time = blob.accessor(pack_f(times), FLOAT, NKEYS, 'SCALAR', None,
                           [times[0]], [times[-1]])
    samplers, channels = [], []
    a_tr = blob.accessor(pack_f([c for t in trans for c in t]), FLOAT, NKEYS, 'VEC3')
    samplers.append({'input': a_time, 'interpolation': 'LINEAR', 'output': a_tr})
    channels.append({'sampler': 0, 'target': {'node': 1 + JOINT_INDEX['hips'],
                                              'path': 'translation'}})
    for n in ANIMATED:
        a_r = blob.accessor(pack_f([c for q in rot[n] for c in q]), FLOAT, NKEYS, 'VEC4')
        samplers.append({'input': a_time, 'interpolation': 'LINEAR', 'output': a_r})
        channels.append({'sampler': len(samplers) - 1,
                         'target': {'node': 1 + JOINT_INDEX[n], 'path': 'rotation'}})

    # Nodes: 0 = scene root, 1..17 = joints (skin order), 18 = skinned mesh.
    nodes = [{'name': 'mannequin',
              'children': [1 + JOINT_INDEX['hips'], 1 + len(JOINT_NAMES)]}]
    for name in JOINT_NAMES:
        t, q = LOCAL_REST[name]
        node = {'name': name, 'translation': list(t), 'rotation': list(q)}
        kids = [1 + i for i, n in enumerate(JOINT_NAMES) if JOINT_PARENT[n] == name]
        if kids:
            node['children'] = kids
        nodes.append(node)
    nodes.append({'name': 'mannequin_mesh', 'mesh': 0, 'skin': 0})

    gltf = {
        'asset': {'version': '2.0', 'generator': 'drape make_mannequin.py'},
        'scene': 0,
        'scenes': [{'name': 'mannequin', 'nodes': [0]}],
        'nodes': nodes,
        'meshes': [{'name': 'mannequin', 'primitives': [{
            'attributes': {'POSITION': a_pos, 'NORMAL': a_nrm,
                           'JOINTS_0': a_jnt, 'WEIGHTS_0': a_wgt},
            'indices': a_idx, 'mode': 4, 'material': 0}]}],
        'materials': [{'name': 'mannequin_grey',
                       'pbrMetallicRoughness': {'baseColorFactor': [0.7, 0.7, 0.7, 1.0],
                                                'metallicFactor': 0.0,
                                                'roughnessFactor': 0.8}}],
        'skins': [{'name': 'mannequin_skin', 'inverseBindMatrices': a_ibm,
                   'skeleton': 1 + JOINT_INDEX['hips'],
                   'joints': [1 + i for i in range(len(JOINT_NAMES))]}],
        'animations': [{'name': 'walk', 'channels': channels, 'samplers': samplers}],
        'accessors': blob.accessors,
        'bufferViews': blob.views,
        'buffers': [{'byteLength': len(blob.data),
                     'uri': 'data:application/octet-stream;base64,'
                            + base64.b64encode(bytes(blob.data)).decode('ascii')}],
    }
    return gltf


def main(argv):
    if len(argv) != 2:
        sys.stderr.write('usage: make_mannequin.py OUTPUT.gltf\n')
        return 2
    text = json.dumps(build_gltf(), indent=1, ensure_ascii=True) + '\n'
    with open(argv[1], 'w', encoding='ascii', newline='\n') as f:
        f.write(text)
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
