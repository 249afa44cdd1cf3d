#!/usr/bin/env python3
"""Writes scenarios/fleet_large.yaml: a 10 x 6 grid of subsea Christmas trees for fleet scale tests.

Regenerate (deterministic: the same file every time, any Python 3):

    python3 tests/maps/make_large_field.py > scenarios/fleet_large.yaml

and commit both this script and the YAML. Counts, footprints, heights and which faces carry
valves come from a fixed-seed SplitMix64 stream written out here, so the output does not depend
on Python's `random` module. The script checks the layout rules of scenarios/two_xt.yaml before
writing (footprints 0.5-0.8 m, valves 0.5 m off a face, >= 1.2 m of water between footprints,
valves >= 1.0 m from the edges and >= 0.8 m apart) and fails loudly if a change breaks one.
"""
import math
import sys

SEED = 20240601
COLUMNS, ROWS = 10, 6           # XTs along x, along y
PITCH_M = 5.0                   # centre-to-centre spacing of the grid (m)
FIRST_CENTRE_M = (2.2, 2.7)     # centre of the south-west XT (m); a start lane stays free below
WORKSPACE_M = (49.4, 30.4)      # width, height (m)
JITTER_STEPS = 5                # centres move by up to 5 x 0.05 m = 0.25 m either way
VALVE_OFFSET_M = 0.5            # valve distance from its footprint face (m)
SIGMA_M = 0.35
VEHICLES = 8
HOTSPOTS = 6                    # valves at weight 10 in the "hotspots" profile

MIN_GAP_M = 1.2                 # free water between two footprints
MIN_EDGE_M = 1.0                # valve to workspace edge
MIN_VALVE_SPACING_M = 0.8       # between any two valves
MIN_VALVE_TO_OTHER_XT_M = 1.0   # valve to a footprint not its own


class SplitMix64:
    """Sebastiano Vigna's SplitMix64: tiny, fixed and the same everywhere."""

    def __init__(self, seed):
        self.state = seed & 0xFFFFFFFFFFFFFFFF

    def next(self):
        self.state = (self.state + 0x9E3779B97F4A7C15) & 0xFFFFFFFFFFFFFFFF
        z = self.state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
        return z ^ (z >> 31)

    def below(self, n):
        """An integer in [0, n) (the tiny modulo bias does not matter here)."""
        return self.next() % n


def q(x):
    """Rounds to the 0.05 m grid the layout lives on, so the file reads cleanly."""
    return round(round(x / 0.05) * 0.05, 2)


# Outward unit normal and the axis along the face, for south, east, north, west.
FACES = {"S": ((0, -1), (1, 0)), "E": ((1, 0), (0, 1)), "N": ((0, 1), (1, 0)), "W": ((-1, 0), (0, 1))}
FACE_ORDER = ["S", "E", "N", "W"]


def make_tree(rng, index, centre):
    count = 3 + rng.below(3)                       # 3, 4 or 5 valves
    turn = rng.below(4)
    faces = FACE_ORDER[turn:] + FACE_ORDER[:turn]  # which face comes first
    size = [0.5 + 0.1 * rng.below(4), 0.5 + 0.1 * rng.below(4)]
    if count == 5:
        # Two valves share the first face, at its two ends: that face is made 0.8 m long.
        along_axis = 0 if FACES[faces[0]][1] == (1, 0) else 1
        size[along_axis] = 0.8
    size = [round(s, 1) for s in size]
    height = round(2.0 + 0.1 * rng.below(11), 1)
    slots = []                                     # (face, offset along the face)
    if count == 3:
        used = faces[:3]
    else:
        used = faces[:4]
    for face in used:
        slots.append((face, 0.05 * (rng.below(7) - 3)))   # -0.15 .. 0.15 m
    if count == 5:
        slots[0] = (faces[0], -0.4)
        slots.append((faces[0], 0.4))

    def place(face, offset):
        (nx, ny), (ax, ay) = FACES[face]
        half_normal = size[0] / 2 if nx else size[1] / 2
        d = half_normal + VALVE_OFFSET_M
        return (q(centre[0] + nx * d + ax * offset), q(centre[1] + ny * d + ay * offset))

    positions = [place(face, offset) for face, offset in slots]
    # A valve too near another of the same XT goes back to the middle of its face.
    for i in range(len(positions)):
        for j in range(len(positions)):
            if i != j and math.dist(positions[i], positions[j]) < MIN_VALVE_SPACING_M:
                face, offset = slots[j]
                if abs(offset) < 0.4:
                    slots[j] = (face, 0.0)
                    positions[j] = place(face, 0.0)
    return {"name": "XT-%02d" % index, "center": centre, "size": size, "height": height,
            "valves": positions, "faces": [f for f, _ in slots]}


def rect_gap(a, b):
    """Free water between two footprints (m): the larger of the per-axis gaps."""
    gx = abs(a["center"][0] - b["center"][0]) - (a["size"][0] + b["size"][0]) / 2
    gy = abs(a["center"][1] - b["center"][1]) - (a["size"][1] + b["size"][1]) / 2
    return max(gx, gy)


def point_to_rect(p, tree):
    dx = max(abs(p[0] - tree["center"][0]) - tree["size"][0] / 2, 0.0)
    dy = max(abs(p[1] - tree["center"][1]) - tree["size"][1] / 2, 0.0)
    return math.hypot(dx, dy)


def check(trees, vehicles):
    w, h = WORKSPACE_M
    for i, a in enumerate(trees):
        assert all(0.5 - 1e-9 <= s <= 0.8 + 1e-9 for s in a["size"]), a["name"]
        for b in trees[i + 1:]:
            assert rect_gap(a, b) >= MIN_GAP_M - 1e-9, (a["name"], b["name"], rect_gap(a, b))
        for p in a["valves"]:
            assert abs(point_to_rect(p, a) - VALVE_OFFSET_M) < 1e-9, (a["name"], p)
            assert min(p[0], p[1], w - p[0], h - p[1]) >= MIN_EDGE_M - 1e-9, (a["name"], p)
            for b in trees:
                if b is not a:
                    assert point_to_rect(p, b) >= MIN_VALVE_TO_OTHER_XT_M - 1e-9, (a["name"], p, b["name"])
    valves = [p for t in trees for p in t["valves"]]
    for i in range(len(valves)):
        for j in range(i + 1, len(valves)):
            assert math.dist(valves[i], valves[j]) >= MIN_VALVE_SPACING_M - 1e-9, (valves[i], valves[j])
    for v in vehicles:
        assert all(point_to_rect(v, t) >= 1.0 for t in trees), v
    for i in range(len(vehicles)):
        for j in range(i + 1, len(vehicles)):
            assert math.dist(vehicles[i], vehicles[j]) >= 1.0


def fmt(x):
    return ("%.2f" % x).rstrip("0").rstrip(".") if x != int(x) else "%.1f" % x


def flow_weights(names, weights, indent):
    """A flow map of weights wrapped at 10 entries a line."""
    items = ["%s: %s" % (n, weights[n]) for n in names]
    lines = [", ".join(items[i:i + 10]) for i in range(0, len(items), 10)]
    return "{" + (",\n" + " " * (indent + 1)).join(lines) + "}"


def main():
    rng = SplitMix64(SEED)
    trees = []
    for row in range(ROWS):
        for col in range(COLUMNS):
            cx = FIRST_CENTRE_M[0] + col * PITCH_M + 0.05 * (rng.below(2 * JITTER_STEPS + 1) - JITTER_STEPS)
            cy = FIRST_CENTRE_M[1] + row * PITCH_M + 0.05 * (rng.below(2 * JITTER_STEPS + 1) - JITTER_STEPS)
            trees.append(make_tree(rng, len(trees) + 1, (q(cx), q(cy))))
    names = []
    for tree in trees:
        tree["valve_names"] = []
        for _ in tree["valves"]:
            names.append("P%d" % (len(names) + 1))
            tree["valve_names"].append(names[-1])
    assert len(trees) >= 50 and len(names) >= 200, (len(trees), len(names))
    # Vehicles 4.3 m apart on a lane 0.6 m in from the south edge, below the first row's valves.
    vehicles = [(1.5 + 4.3 * k, 0.6) for k in range(VEHICLES)]
    check(trees, vehicles)

    hot = []
    while len(hot) < HOTSPOTS:
        name = names[rng.below(len(names))]
        if name not in hot:
            hot.append(name)
    routine = {n: 1 for n in names}
    hotspots = {n: (10 if n in hot else 1) for n in names}
    floor = 0.001
    assert floor * len(names) < 1

    out = []
    w = out.append
    w("# SAGE Fleet scenario for scale tests: a %d x %d grid of subsea Christmas trees (%d XTs, %d valves)"
      % (COLUMNS, ROWS, len(trees), len(names)))
    w("# and %d BlueROV2s listed (sage ... --vehicles N adds more along the south edge or keeps fewer)." % VEHICLES)
    w("#")
    w("# GENERATED by tests/maps/make_large_field.py (seed %d); do not edit by hand. Regenerate with" % SEED)
    w("#     python3 tests/maps/make_large_field.py > scenarios/fleet_large.yaml")
    w("#")
    w("# Units are in the field names (_m metres, _s seconds, _hz hertz, _mps metres per second, _rad")
    w("# radians); x along width, y along height, origin at a corner. The layout follows the rules of")
    w("# scenarios/two_xt.yaml: footprints 0.5-0.8 m, each valve 0.5 m off a face of its XT, XT centres")
    w("# on a %s m grid (jittered up to 0.25 m) so at least %.1f m of water lies between footprints," % (fmt(PITCH_M), MIN_GAP_M))
    w("# valves at least %.1f m from the edges and %.1f m from each other." % (MIN_EDGE_M, MIN_VALVE_SPACING_M))
    w("")
    w("name: fleet_large")
    w("")
    w("workspace: {width_m: %s, height_m: %s}" % (fmt(WORKSPACE_M[0]), fmt(WORKSPACE_M[1])))
    w("")
    w("duration_s: 300")
    w("control_rate_hz: 10")
    w("physics_rate_hz: 50")
    w("visit_radius_m: 0.3")
    w("rearm_radius_m: 0.45")
    w("seed: 1")
    w("")
    w("ergodic:")
    w("  basis_order: 40             # the cap: finest half-wavelength %s m / 39 = %.2f m" % (fmt(WORKSPACE_M[0]), WORKSPACE_M[0] / 39))
    w("  forgetting_time_s: .inf")
    w("")
    w("guard:")
    w("  enabled: true")
    w("  weight_floor: %s         # %d valves x %s = %.0f %% of the risk on floors" % (floor, len(names), floor, 100 * floor * len(names)))
    w("  revisit_bound_s: 180")
    w("")
    w("astar:")
    w("  grid_resolution_m: 0.1")
    w("  clearance_m: 0.3")
    w("  wait_per_lap_s: 1.0")
    w("")
    w("# Coverage reports every 2 s: at K = 40 one report is 12.8 kB, and a 1,000-vehicle fleet at 0.5 s")
    w("# would put 26 MB/s on the loopback for little gain.")
    w("fleet: {assignment: regions, coverage_period_s: 2.0, liveliness_lease_s: 0.5}")
    w("")
    w("structures:")
    for tree in trees:
        w("  - name: %s" % tree["name"])
        w("    center_m: [%s, %s]" % (fmt(tree["center"][0]), fmt(tree["center"][1])))
        w("    size_m: [%s, %s]" % (fmt(tree["size"][0]), fmt(tree["size"][1])))
        w("    height_m: %s" % fmt(tree["height"]))
        w("    valves:")
        for name, p in zip(tree["valve_names"], tree["valves"]):
            w("      - {name: %s, position_m: [%s, %s], sigma_m: %s}" % (name, fmt(p[0]), fmt(p[1]), SIGMA_M))
    w("")
    w("vehicles:")
    for k, (x, y) in enumerate(vehicles):
        w("  - {name: rov%d, start_m: [%s, %s], start_heading_rad: 1.5708, model: bluerov2, transit_speed_mps: 0.7}"
          % (k + 1, fmt(x), fmt(y)))
    w("")
    w("default_profile: routine")
    w("")
    w("profiles:")
    w("  routine:                    # every valve alike")
    w("    weights: " + flow_weights(names, routine, len("    weights: ")))
    w("  hotspots:                   # %s at weight 10, the rest 1" % ", ".join(hot))
    w("    weights: " + flow_weights(names, hotspots, len("    weights: ")))
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
