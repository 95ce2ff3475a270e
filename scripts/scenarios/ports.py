"""The corneal ports of a drill, placed exactly as procedures/scene/tool_ports.cpp default_ports()
places them, and the aiming that makes a scripted hand pivot in its port (issue 7 item 2).

default_ports: centre `tool_eye.port_inset_mm` inside the limbus at the drill's clock hour
(guidance.incision_site for "main", guidance.side_port for "side"), at mid-thickness of the cornea
(halfway between the anterior and posterior corneal spheres); the tunnel's axis runs inward and
down at `tool_eye.entry_angle_deg` below the iris plane. The eye is data/eye/standard_eye.json
(the scenarios' eye). tests/procedures/scene/test_drill_scenarios.cpp checks that the generated
experts' shafts pass through the C++ port centres, so this copy cannot drift unnoticed.

A scripted expert pivots in the incision: whenever its tip is inside the eye, the tool's shaft
(the tool frame's +z, tip -> handle; ToolState.quat * UnitZ) passes through its port's centre.
`aim` turns a sample's quaternion by the smallest rotation that does it (the tool's roll about
its shaft, e.g. the cystotome's or keratome's blade, stays as close as it can), and `pivot_track`
inserts samples where the tracks' linear/slerp interpolation would let the shaft drift off the
centre by more than `tol_mm`; inserted samples are the engine's own interpolation of position,
grip and pedal (engine/io/track.cpp), so the tip's path and the hand's controls are unchanged.
"""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")


def sub(a, b): return [a[i] - b[i] for i in range(3)]
def add(a, b): return [a[i] + b[i] for i in range(3)]
def mul(s, a): return [s * v for v in a]
def dot(a, b): return sum(a[i] * b[i] for i in range(3))
def cross(a, b): return [a[1]*b[2] - a[2]*b[1], a[2]*b[0] - a[0]*b[2], a[0]*b[1] - a[1]*b[0]]
def norm(a): return math.sqrt(dot(a, a))
def unit(a): n = norm(a); return mul(1 / n, a)


def eye_params(path=None):
    with open(path or os.path.join(ROOT, "data", "eye", "standard_eye.json")) as f:
        return json.load(f)


def default_ports(drill, params=None):
    """{"main": (centre, axis), "side": (centre, axis)} for data/drills/<drill>.json."""
    p = params or eye_params()
    with open(os.path.join(ROOT, "data", "drills", drill + ".json")) as f:
        guidance = json.load(f)["guidance"]
    c, t = p["cornea"], p["tool_eye"]
    ra, rp = c["anterior_radius_mm"], c["posterior_radius_mm"]
    ca = c["posterior_apex_z_mm"] + c["central_thickness_mm"] - ra  # anterior sphere's centre z
    cp = c["posterior_apex_z_mm"] - rp                              # posterior sphere's centre z
    rho = 0.5 * c["limbus_diameter_mm"] - t["port_inset_mm"]
    z = 0.5 * (ca + math.sqrt(ra * ra - rho * rho) + cp + math.sqrt(rp * rp - rho * rho))
    angle = math.radians(t["entry_angle_deg"])
    ports = {}
    for name, key in (("main", "incision_site"), ("side", "side_port")):
        azimuth = math.radians((3.0 - guidance[key]["clock_hour"]) * 30.0)
        radial = [math.cos(azimuth), math.sin(azimuth), 0.0]
        centre = add(mul(rho, radial), [0.0, 0.0, z])
        axis = unit(add(mul(-math.cos(angle), radial), [0.0, 0.0, -math.sin(angle)]))
        ports[name] = (centre, axis)
    return ports


# Quaternions [w, x, y, z] as in the scenario files.
def qmul(a, b):
    return [a[0]*b[0] - a[1]*b[1] - a[2]*b[2] - a[3]*b[3],
            a[0]*b[1] + a[1]*b[0] + a[2]*b[3] - a[3]*b[2],
            a[0]*b[2] - a[1]*b[3] + a[2]*b[0] + a[3]*b[1],
            a[0]*b[3] + a[1]*b[2] - a[2]*b[1] + a[3]*b[0]]


def qunit(q):
    n = math.sqrt(sum(v * v for v in q))
    return [v / n for v in q]


def shaft_of(q):
    """The tool's +z axis (tip -> handle) for the unit quaternion q."""
    w, x, y, z = qunit(q)
    return [2 * (x*z + w*y), 2 * (y*z - w*x), 1 - 2 * (x*x + y*y)]


def swing(a, b):
    """The smallest rotation taking unit vector a onto unit vector b."""
    c = dot(a, b)
    if c < -1 + 1e-12:
        raise ValueError("shaft would have to turn half a circle")
    ax = cross(a, b)
    return qunit([1 + c] + ax)


# The bent points (engine/io/tool_shape.hpp): the shaft's axis runs this far beside the tip, along
# the tool frame's +y. The pivot is about the drawn shaft, so it is that axis that is aimed.
BEND_MM = {"cystotome": 0.3, "chopper": 1.0, "hook": 1.0}


def rotate(q, v):
    """v turned by the unit quaternion q."""
    u = qunit(q)
    return qmul(qmul(u, [0.0] + list(v)), [u[0], -u[1], -u[2], -u[3]])[1:]


def offset_from(tip, shaft, centre):
    """Distance of the shaft's line from the port centre, mm."""
    d = sub(centre, tip)
    return norm(sub(d, mul(dot(d, shaft), shaft)))


def axis_offset(tip, q, centre, bend=0.0):
    """Distance of the shaft's axis (through tip + q·(0, bend, 0)) from the port centre, mm."""
    return offset_from(add(tip, rotate(q, [0.0, bend, 0.0])), shaft_of(q), centre)


def aimed(tip, q, centre, axis, bend=0.0, blend_mm=1.0):
    """q turned so that the shaft from `tip` passes through `centre`. A tip at the centre or out
    past it (the tool not yet in, or in the tunnel) takes the tunnel's outward axis. With a bent
    point it is the shaft's axis, `bend` beside the tip, that is aimed, as
    procedures/scene/port_pivot does: from `bend` past the centre, blended in over `blend_mm`
    from the line through the tip (closer in, the axis could pass the centre only across the
    tunnel)."""
    d = sub(centre, tip)
    past = dot(d, mul(-1, axis))
    want = unit(d) if past > 1e-6 else mul(-1, axis)
    line = qunit(qmul(swing(shaft_of(q), want), qunit(q)))
    w = min(1.0, max(0.0, (past - bend) / blend_mm))
    if bend == 0 or w <= 0:
        return line
    s = math.sqrt(max(0.0, dot(d, d) - bend * bend))
    full = qunit(qmul(swing(unit(rotate(q, [0.0, bend, s])), unit(d)), qunit(q)))
    return slerp(line, full, w)


def slerp(a, b, u):
    c = sum(a[i] * b[i] for i in range(4))
    if c < 0:
        b, c = [-v for v in b], -c
    if c > 1 - 1e-12:
        return qunit([a[i] + u * (b[i] - a[i]) for i in range(4)])
    th = math.acos(c)
    s = math.sin(th)
    return qunit([(math.sin((1 - u) * th) * a[i] + math.sin(u * th) * b[i]) / s for i in range(4)])


def lerp(a, b, u): return [a[i] + u * (b[i] - a[i]) for i in range(len(a))]


def pivot_track(track, centre, axis, inside, tol_mm=0.01, max_depth=8, bend=0.0):
    """Aims every sample whose tip satisfies inside(tip) through `centre`, and inserts samples
    (the engine's interpolation of pos, grip and pedal) wherever the interpolated shaft between
    two aimed samples would pass the centre farther than tol_mm from where the aim puts it.
    `bend`: the tool's bent point (BEND_MM), whose shaft's axis is aimed."""
    def sample_at(a, b, u):
        s = {"t": a["t"] + u * (b["t"] - a["t"]), "pos": lerp(a["pos"], b["pos"], u),
             "quat": slerp(a["quat"], b["quat"], u)}
        for k in ("grip", "pedal"):
            if k in a or k in b:
                s[k] = a.get(k, 0) + u * (b.get(k, 0) - a.get(k, 0))
        return s

    def aim(s):
        if inside(s["pos"]):
            s["quat"] = aimed(s["pos"], s["quat"], centre, axis, bend)
        return s

    def worst(a, b):
        e = 0.0
        for k in range(1, 8):
            s = sample_at(a, b, k / 8)
            if inside(s["pos"]) and dot(sub(centre, s["pos"]), mul(-1, axis)) > 1e-6:
                off = axis_offset(s["pos"], s["quat"], centre, bend)
                if bend:  # where the aim itself cannot reach the centre yet, from where it does
                    off = abs(off - axis_offset(s["pos"], aimed(s["pos"], s["quat"], centre, axis,
                                                                 bend), centre, bend))
                e = max(e, off)
        return e

    def fill(a, b, depth):
        if depth >= max_depth or b["t"] - a["t"] <= 1e-3 or worst(a, b) <= tol_mm:
            return [b]
        m = aim(sample_at(a, b, 0.5))
        return fill(a, m, depth + 1) + fill(m, b, depth + 1)

    src = [dict(s) for s in track]
    for s in src:
        aim(s)
    out = [src[0]]
    for a, b in zip(src, src[1:]):
        out += fill(a, b, 0)
    for s in out:
        s["t"] = round(s["t"], 6) + 0.0
        s["pos"] = [round(v, 4) + 0.0 for v in s["pos"]]
        s["quat"] = [round(v, 6) + 0.0 for v in qunit(s["quat"])]
        for k in ("grip", "pedal"):
            if k in s:
                s[k] = round(s[k], 6) + 0.0
    return out


def inside_eye(params=None):
    """A tip below the anterior corneal surface within the limbus: in the stroma or the chamber."""
    p = params or eye_params()
    c = p["cornea"]
    ra = c["anterior_radius_mm"]
    ca = c["posterior_apex_z_mm"] + c["central_thickness_mm"] - ra
    limbus = 0.5 * c["limbus_diameter_mm"]

    def inside(tip):
        rho = math.hypot(tip[0], tip[1])
        return rho < limbus and tip[2] < ca + math.sqrt(ra * ra - rho * rho)
    return inside
