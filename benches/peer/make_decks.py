#!/usr/bin/env python3
"""Write the peer benchmark's CalculiX decks and the matching mpfem cases.

Three jobs (units mm, N, MPa, s; plane strain, forces per unit thickness):

  disc   one aluminium disc (R = 10 mm) pressed between two rigid frictionless plates to
         30 % of its diameter (each plate travels 3 mm). Both codes model the quarter
         x >= 0, y >= 0 with ux = 0 on x = 0 and uy = 0 on y = 0 (exact symmetry) and one
         plate on top moving down 3 mm over t = 0..1 s; the plate force of the quarter is
         half the whole disc's (2D: the plate meets half the contact patch).
  die2   the 2 x 2 aluminium discs of jobs/compaction/discs_2x2_lateral.toml: a 100 mm
         square die at solid ratio 0.70, the left and right walls moving in at 10 mm/s,
         top and bottom fixed, frictionless, full model, up to a nominal solid ratio of
         0.95 (initial particle area over the die's area); in both codes every disc's
         horizontal diameter is held at u_y = 0 (HOLD below: exact for the symmetric
         solution, it takes away the neutral up-and-down mode of the loose discs).
  die4   the same with 4 x 4 discs.

Both codes get the same material: J2 plasticity, E = 64,100 MPa, nu = 0.3, the isotropic
hardening of the paper's Table 1 (jobs/data/aluminium_250c.csv, mpfem's preset
aluminium_250c) converted to true stress vs equivalent plastic strain exactly as
src/material/hardening.rs does (eps_p = eps - sigma/E, the first point set to 0), perfectly
plastic beyond the last point in both codes.

CalculiX side (written here, our own decks): a structured O-grid of each disc (a square
core and curved blocks, n elements on every 45 degree arc), plane-strain elements
(--element: CPE4, CPE4R, CPE8R, CPE8, or C3D8I/C3D8R/C3D8 as one layer of bricks 1 mm thick
with u_z = 0; the benchmark uses CPE4, the only one that reached the end on fine meshes, see
docs/peer.md); rigid walls as meshed plates whose nodes are all prescribed (the wall force
is the total of their reaction forces, *NODE PRINT ... TOTALS=ONLY); frictionless
face-to-face penalty contact (TYPE=SURFACE TO SURFACE, linear pressure-overclosure with slope
K, 10 E per mm by default; PEER_CCX_CONTACT=n2s writes node-to-surface contact instead);
NLGEOM static steps with automatic incrementation. The discs of the die jobs touch nothing
at the start: CalculiX's die starts where their rigid approach ends, with each disc's
diameter pinned (HOLD) and a weak spring along x at its centre (SPRING_X).

mpfem side: the same geometry with mpfem's defaults (barrier contact, frictionless walls);
the pinned die's discs as two half discs each (HALF_GAP).

Usage:
  make_decks.py OUTDIR --job disc --ccx-n 16 --mpfem-h 0.5 [--element CPE4] [--name NAME]
writes OUTDIR/NAME.inp (CalculiX) and OUTDIR/NAME.toml (mpfem), and OUTDIR/NAME.json with
what the runner needs to read the results (the times of the quantities, the wall lengths).
"""

import argparse
import json
import math
import os

E = 64100.0
NU = 0.3
# Table 1 of the paper: uniaxial total strain vs true stress (MPa)
TABLE1 = [(0.0, 0.0), (0.0011, 70.5), (0.0031, 111.2), (0.0087, 129.1), (0.016, 130.2)]


def plastic_table():
    """(stress, plastic strain) pairs as mpfem's HardeningTable::from_total_strain makes them."""
    pts = [p for p in TABLE1 if not (p[0] == 0.0 and p[1] == 0.0)]
    out = []
    for k, (eps, sig) in enumerate(pts):
        ep = 0.0 if k == 0 else eps - sig / E
        out.append((sig, ep))
    return out


# ---------------------------------------------------------------------------------------
# meshes


class Mesh:
    """Nodes (merged by position) and quadrilaterals (4 or 8 nodes, counter-clockwise)."""

    def __init__(self, tol):
        self.tol = tol
        self.xy = []
        self.key = {}
        self.elems = []

    def node(self, p):
        k = (round(p[0] / self.tol), round(p[1] / self.tol))
        if k not in self.key:
            self.key[k] = len(self.xy)
            self.xy.append((p[0], p[1]))
        return self.key[k]

    def block(self, f, nu, nv, order):
        """Structured block of nu x nv elements on the map f(u, v), u, v in [0, 1]."""
        q = order
        ids = [[self.node(f(i / (q * nu), j / (q * nv))) for j in range(q * nv + 1)]
               for i in range(q * nu + 1)]
        for i in range(nu):
            for j in range(nv):
                a, b = q * i, q * j
                c = [ids[a][b], ids[a + q][b], ids[a + q][b + q], ids[a][b + q]]
                if q == 2:
                    c += [ids[a + 1][b], ids[a + 2][b + 1], ids[a + 1][b + 2], ids[a][b + 1]]
                self.elems.append(c)


def coons(bottom, right, top, left):
    """Transfinite map of four boundary curves (bottom(u), top(u), left(v), right(v))."""
    p00, p10, p01, p11 = bottom(0), bottom(1), top(0), top(1)

    def f(u, v):
        return tuple(
            (1 - v) * bottom(u)[k] + v * top(u)[k] + (1 - u) * left(v)[k] + u * right(v)[k]
            - ((1 - u) * (1 - v) * p00[k] + u * (1 - v) * p10[k] + (1 - u) * v * p01[k] + u * v * p11[k])
            for k in range(2))
    return f


CORE = 0.42   # core corner at (CORE, CORE) R
BULGE = 0.08  # core sides bulged outward by BULGE * CORE * R at their middle


def quarter_blocks(n, m):
    """The three blocks (map, nu, nv) of the quarter O-grid of the unit disc, x, y >= 0."""
    c, b = CORE, BULGE * CORE

    def core_right(v):  # x = c + b (1 - (y/c)^2), y = c v
        y = c * v
        return (c + b * (1 - v * v), y)

    def core_top(u):
        return (c * u, c + b * (1 - u * u))

    def arc(t0, t1):
        return lambda s: (math.cos(t0 + (t1 - t0) * s), math.sin(t0 + (t1 - t0) * s))

    def line(p, q):
        return lambda s: (p[0] + (q[0] - p[0]) * s, p[1] + (q[1] - p[1]) * s)

    corner = core_right(1.0)
    a45 = (math.cos(math.pi / 4), math.sin(math.pi / 4))
    core = coons(line((0.0, 0.0), (c + b, 0.0)), core_right, core_top, line((0.0, 0.0), (0.0, c + b)))
    # block between the core's right side and the arc 0..45 degrees: u outward, v upward
    east = coons(line((c + b, 0.0), (1.0, 0.0)), arc(0.0, math.pi / 4), line(corner, a45), core_right)
    # block between the core's top side and the arc 45..90 degrees: u rightward, v outward
    north = coons(core_top, line(corner, a45), arc(math.pi / 2, math.pi / 4), line((0.0, c + b), (0.0, 1.0)))
    return [(core, n, n), (east, m, n), (north, n, m)]


def disc_mesh(center, R, n, order, part):
    """O-grid of a disc (part 'quarter': x, y >= 0 about the centre; 'full': all four)."""
    # radial divisions: the mean core-to-circle gap (about 0.47 R) over the arc's element size
    m = max(1, round(0.47 * n / (math.pi / 4)))
    mesh = Mesh(1e-9 * R)
    signs = [(1, 1)] if part == "quarter" else [(1, 1), (-1, 1), (-1, -1), (1, -1)]
    for sx, sy in signs:
        for f, nu, nv in quarter_blocks(n, m):
            start = len(mesh.elems)
            mesh.block(lambda u, v, f=f: (center[0] + sx * R * f(u, v)[0], center[1] + sy * R * f(u, v)[1]),
                       nu, nv, order)
            if sx * sy < 0:  # a mirror turns the elements clockwise: renumber
                for e in mesh.elems[start:]:
                    c4 = [e[0], e[3], e[2], e[1]]
                    if order == 2:
                        c4 += [e[7], e[6], e[5], e[4]]
                    e[:] = c4
    return mesh


def outer_faces(mesh, center, R):
    """(element index, face number 1..4) of the element sides on the circle."""
    out = []
    for k, e in enumerate(mesh.elems):
        for f in range(4):
            a, b = mesh.xy[e[f]], mesh.xy[e[(f + 1) % 4]]
            ra = math.hypot(a[0] - center[0], a[1] - center[1])
            rb = math.hypot(b[0] - center[0], b[1] - center[1])
            if abs(ra - R) < 1e-7 * R and abs(rb - R) < 1e-7 * R:
                out.append((k, f + 1))
    return out


# ---------------------------------------------------------------------------------------
# CalculiX deck


class Deck:
    def __init__(self, title):
        self.lines = ["** " + title, "** written by benches/peer/make_decks.py"]
        self.nodes = []   # (id, x, y, z)
        self.nid = 0
        self.eid = 0

    def add_mesh(self, mesh, etype, elset):
        """Add a mesh; returns (node id before its first node, id of its first element) and,
        for a 3D slab (C3D8, C3D8I, C3D8R: one layer of bricks 1 mm thick, z from 0 to 1),
        the ids of the back layer's nodes follow those of the front layer."""
        base = self.nid
        slab = etype.startswith("C3D")
        layers = (0.0, 1.0) if slab else (0.0,)
        for z in layers:
            for (x, y) in mesh.xy:
                self.nid += 1
                self.nodes.append((self.nid, x, y, z))
        first = self.eid + 1
        nn = len(mesh.xy)
        self.lines.append("*ELEMENT, TYPE=%s, ELSET=%s" % (etype, elset))
        for e in mesh.elems:
            self.eid += 1
            ids = [base + 1 + i for i in e]
            if slab:
                ids = ids[:4] + [i + nn for i in ids[:4]]
            self.lines.append(", ".join(str(v) for v in [self.eid] + ids))
        return base, first

    def nodes_where(self, lo, hi, pred):
        """Ids of the nodes lo < id <= hi whose (x, y) satisfies pred (both layers of a slab)."""
        return [n[0] for n in self.nodes[lo:hi] if pred(n[1], n[2])]

    def nset(self, name, ids):
        self.lines.append("*NSET, NSET=%s" % name)
        ids = list(ids)
        for i in range(0, len(ids), 12):
            self.lines.append(", ".join(str(v) for v in ids[i:i + 12]))

    def surface(self, name, faces, slab):
        """Element faces (element id, side 1..4 of the quadrilateral); on a slab of bricks the
        side k of the quadrilateral is the brick's face S(k + 2)."""
        self.lines.append("*SURFACE, NAME=%s, TYPE=ELEMENT" % name)
        for (e, f) in faces:
            self.lines.append("%d, S%d" % (e, f + 2 if slab else f))

    def text(self):
        head = ["*NODE, NSET=NALL"] + ["%d, %.12g, %.12g, %.12g" % n for n in self.nodes]
        return "\n".join(self.lines[:2] + head + self.lines[2:]) + "\n"


def plate(x0, y0, x1, y1, nx):
    """A plate (rectangle) of nx x 1 four-node elements."""
    mesh = Mesh(1e-9 * max(abs(x1 - x0), abs(y1 - y0)))
    mesh.block(lambda u, v: (x0 + (x1 - x0) * u, y0 + (y1 - y0) * v), nx, 1, 1)
    return mesh


def plate_face(mesh, side):
    """Faces of a plate mesh on its 'bottom', 'top', 'left' or 'right' side."""
    xs = [p[0] for p in mesh.xy]
    ys = [p[1] for p in mesh.xy]
    want = {"bottom": (1, min(ys)), "top": (1, max(ys)), "left": (0, min(xs)), "right": (0, max(xs))}[side]
    out = []
    for k, e in enumerate(mesh.elems):
        for f in range(4):
            a, b = mesh.xy[e[f]], mesh.xy[e[(f + 1) % 4]]
            if abs(a[want[0]] - want[1]) < 1e-9 and abs(b[want[0]] - want[1]) < 1e-9:
                out.append((k, f + 1))
    return out


def material_lines():
    out = ["*MATERIAL, NAME=ALU", "*ELASTIC", "%.1f, %.2f" % (E, NU), "*PLASTIC"]
    out += ["%.6g, %.9g" % p for p in plastic_table()]
    return out


# CalculiX's contact: "f2f" face-to-face penalty (TYPE=SURFACE TO SURFACE, the default) or
# "n2s" node-to-face penalty (TYPE=NODE TO SURFACE, with its small tension sigma_inf at large
# clearance, E/70,000, which holds loose bodies)
CONTACT = os.environ.get("PEER_CCX_CONTACT", "f2f")


def contact_lines(k_contact):
    behaviour = "%.6g" % k_contact if CONTACT == "f2f" else "%.6g, %.6g" % (k_contact, E / 70000.0)
    return ["*SURFACE INTERACTION, NAME=SI", "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR", behaviour]


def contact_pair():
    return "*CONTACT PAIR, INTERACTION=SI, TYPE=%s" % ("SURFACE TO SURFACE" if CONTACT == "f2f" else "NODE TO SURFACE")


def ccx_disc(n, element, k_contact, R=10.0, travel=3.0, dtmax=0.1):
    order = 2 if element.startswith("CPE8") else 1
    d = Deck("peer benchmark: quarter aluminium disc between rigid plates, n = %d, %s" % (n, element))
    disc = disc_mesh((0.0, 0.0), R, n, order, "quarter")
    slab = element.startswith("C3D")
    pelem = "C3D8" if slab else "CPE4"
    base, first = d.add_mesh(disc, element, "DISC")
    top = d.nid
    pl = plate(-0.1 * R, R, 1.6 * R, 1.1 * R, 8)
    pbase, pfirst = d.add_mesh(pl, pelem, "PLATE")
    d.nset("SYMX", d.nodes_where(base, top, lambda x, y: abs(x) < 1e-9))
    d.nset("SYMY", d.nodes_where(base, top, lambda x, y: abs(y) < 1e-9))
    d.nset("PLATEN", range(pbase + 1, d.nid + 1))
    d.surface("SDISC", [(first + e, f) for e, f in outer_faces(disc, (0.0, 0.0), R)], slab)
    d.surface("SPLATE", [(pfirst + e, f) for e, f in plate_face(pl, "bottom")], slab)
    d.lines += material_lines()
    d.lines += ["*SOLID SECTION, ELSET=DISC, MATERIAL=ALU", "1.", "*SOLID SECTION, ELSET=PLATE, MATERIAL=ALU", "1."]
    d.lines += contact_lines(k_contact)
    d.lines += [contact_pair(), "SDISC, SPLATE"]
    d.lines += ["*BOUNDARY", "SYMX, 1, 1", "SYMY, 2, 2", "PLATEN, 1, 1"] + (["NALL, 3, 3"] if slab else [])
    d.lines += ["*TIME POINTS, NAME=TP", "0.333333333333, 0.666666666667, 1."]
    d.lines += ["*STEP, NLGEOM, INC=100000", "*STATIC", "%g, 1., 1e-7, %g" % (min(0.05, dtmax), dtmax),
                "*BOUNDARY", "PLATEN, 2, 2, %.9g" % (-travel),
                "*NODE PRINT, NSET=PLATEN, TOTALS=ONLY, TIME POINTS=TP", "RF",
                "*END STEP"]
    meta = {"job": "disc", "code": "ccx", "n": n, "element": element, "k_contact": k_contact,
            "nodes": d.nid, "elements": len(disc.elems),
            "h": math.pi / 4 * R / n, "R": R, "travel": travel,
            "times": [1 / 3, 2 / 3, 1.0], "labels": ["10%", "20%", "30%"]}
    return d.text(), meta


def die_geometry(nx, ny, width=100.0, solid=0.70):
    r = math.sqrt(solid * width * width / (nx * ny * math.pi))
    centres = [((i + 0.5) * width / nx, (j + 0.5) * width / ny) for j in range(ny) for i in range(nx)]
    return r, centres


def die_times(nx, ny, width, solid0, targets, speed):
    """Times at which the lateral die reaches the nominal solid ratios `targets`."""
    a0 = solid0 * width * width
    return [(width - a0 / (t * width)) / (2.0 * speed) for t in targets]


DIE_TARGETS = [0.80, 0.85, 0.90, 0.93, 0.95]
# springs to the ground at each disc centre in CalculiX's die decks (N/mm): along the walls'
# motion weak (the discs move there by millimetres: 1e-3 N/mm is below 1e-5 of the wall force),
# across it and against rotation (a node r/2 above the centre) stiffer, 10 N/mm: the discs do
# not move that way in the symmetric solution of the 2 x 2 die (the rows of the 4 x 4 die by
# at most a fraction of a millimetre), and weaker springs let Newton's first iterates fling the
# loose discs about (contact elements by the hundreds, no convergence)
SPRING_X = 1e-3
# How the dies hold their discs (docs/peer.md): "pins" (the benchmark) holds every disc's
# horizontal diameter at u_y = 0 in both codes, which the symmetric solution satisfies
# exactly: frictionless discs pressed sideways have no stiffness up or down until they touch
# the fixed walls or the other rows, and the constraint takes that neutral mode away. mpfem
# models each disc as two half discs with uy = 0 on their cuts (HALF_GAP); CalculiX holds the
# nodes of each full disc's diameter. "springs" writes the first cut's unpinned decks
# (mpfem's [[grids]]; in CalculiX springs to the ground at each disc centre), which CalculiX
# does not get past the first contacts and in which mpfem's discs drift.
HOLD = os.environ.get("PEER_DIE_HOLD", "pins")
# CalculiX's time incrementation controls of the die step (I_0, I_R, I_P, I_C, I_L, I_G, I_S,
# I_A): at most 30 iterations an increment (default 16) and 10 cut-backs (default 5)
CONTROLS = os.environ.get("PEER_CCX_CONTROLS", "4, 8, 9, 30, 10, 4, 0, 10")
SPRING_Y = 10.0


def ccx_die(nx, ny, n, element, k_contact, dtmax, width=100.0, solid0=0.70, speed=10.0, end_solid=0.95,
            hold=HOLD):
    order = 2 if element.startswith("CPE8") else 1
    slab = element.startswith("C3D")
    pelem = "C3D8" if slab else "CPE4"
    r, centres = die_geometry(nx, ny, width, solid0)
    tend = die_times(nx, ny, width, solid0, [end_solid], speed)[0]
    # The walls first push the columns of discs together without any resistance (frictionless,
    # no contact yet between the rows): a rigid motion that penalty contact cannot take on
    # (the first contacts push free bodies). CalculiX's model starts where that motion ends:
    # the discs of each row touching (overlapping by 1e-5 r), the side walls touching the
    # outer discs, at t0 = that travel / speed; the rows keep their heights (by symmetry).
    gap = 1e-5 * r
    xs = [0.5 * width + (i - 0.5 * (nx - 1)) * (2 * r - gap) for i in range(nx)]
    centres = [(xs[i], centres[j * nx + i][1]) for j in range(ny) for i in range(nx)]
    x_left = xs[0] - r + gap
    t0 = x_left / speed
    d = Deck("peer benchmark: %d x %d aluminium discs, lateral die compaction, n = %d, %s" % (nx, ny, n, element))
    surf = []
    d_elems, d_first = [], None   # the discs' elements (node ids), id of the first
    centre_nodes = []
    top_nodes = []
    for k, c in enumerate(centres):
        disc = disc_mesh(c, r, n, order, "full")
        base, first = d.add_mesh(disc, element, "D%d" % k)
        nodes_per_disc = d.nid - base
        surf.append([(first + e, f) for e, f in outer_faces(disc, c, r)])
        for e in disc.elems:
            d_elems.append([base + 1 + i for i in e])
        if k == 0:
            d_first = first
        # a slab's nodes of the back layer follow those of the front layer; the springs
        # hold the front layer's nodes (dof 3 is fixed everywhere)
        ic = min(range(len(disc.xy)), key=lambda i: math.hypot(disc.xy[i][0] - c[0], disc.xy[i][1] - c[1]))
        it = min(range(len(disc.xy)), key=lambda i: math.hypot(disc.xy[i][0] - c[0], disc.xy[i][1] - c[1] - 0.5 * r))
        centre_nodes.append(base + 1 + ic)
        top_nodes.append(base + 1 + it)
    # the walls: plates 5 mm thick reaching 5 mm past the die's corners, ten elements long,
    # every node prescribed; the face towards the discs is the contact surface
    t = 0.05 * width
    xl, xr = x_left, width - x_left
    plates = [("LEFT", (xl - t, -t, xl, width + t), "right"), ("RIGHT", (xr, -t, xr + t, width + t), "left"),
              ("BOTTOM", (-t, -t, width + t, 0.0), "top"), ("TOP", (-t, width, width + t, width + t), "bottom")]
    for name, (x0, y0, x1, y1), side in plates:
        mesh = Mesh(1e-9 * width)
        if side in ("left", "right"):
            mesh.block(lambda u, v: (x1 - (x1 - x0) * v, y0 + (y1 - y0) * u), 10, 1, 1)
        else:
            mesh.block(lambda u, v: (x0 + (x1 - x0) * u, y0 + (y1 - y0) * v), 10, 1, 1)
        pbase, pfirst = d.add_mesh(mesh, pelem, "P" + name)
        d.nset(name, range(pbase + 1, d.nid + 1))
        d.surface("S" + name, [(pfirst + e, f) for e, f in plate_face(mesh, side)], slab)
    # each disc's surface split into the halves facing east, west, north and south: a pair
    # takes only the halves that face each other (with whole circles, points on a disc's far
    # side project onto the other disc's far side as deep penetrations)
    dirs = {"E": (1, 0), "W": (-1, 0), "N": (0, 1), "S": (0, -1)}
    xy_of = {nd[0]: (nd[1], nd[2]) for nd in d.nodes}
    for k, faces in enumerate(surf):
        for tag, (dx, dy) in dirs.items():
            half = []
            for e, f in faces:
                el = d_elems[e - d_first]
                a, b = xy_of[el[f - 1]], xy_of[el[f % 4]]
                mx, my = 0.5 * (a[0] + b[0]) - centres[k][0], 0.5 * (a[1] + b[1]) - centres[k][1]
                if mx * dx + my * dy > 0.0:
                    half.append((e, f))
            d.surface("SD%d%s" % (k, tag), half, slab)
    d.lines += material_lines()
    for k in range(len(centres)):
        d.lines += ["*SOLID SECTION, ELSET=D%d, MATERIAL=ALU" % k, "1."]
    for name, _, _ in plates:
        d.lines += ["*SOLID SECTION, ELSET=P%s, MATERIAL=ALU" % name, "1."]
    # hold="pins": u_y = 0 on every disc's horizontal diameter (exact for the symmetric
    # solution, see HOLD) and only the weak spring along x; hold="springs": springs to the
    # ground at each disc's centre (x, y) and r/2 above it (x: rotation)
    springs = ((1, centre_nodes, "SX", SPRING_X), (2, centre_nodes, "SY", SPRING_Y), (1, top_nodes, "SR", SPRING_Y))
    if hold == "pins":
        pins = []
        for k, c in enumerate(centres):
            lo, hi = k * nodes_per_disc, (k + 1) * nodes_per_disc
            pins += d.nodes_where(lo, hi, lambda x, y, c=c: abs(y - c[1]) < 1e-7 * r)
        d.nset("PINS", pins)
        springs = ((1, centre_nodes, "SX", SPRING_X),)
    for dof, nodes, tag, spring_k in springs:
        d.lines.append("*ELEMENT, TYPE=SPRING1, ELSET=%s" % tag)
        for nd in nodes:
            d.eid += 1
            d.lines.append("%d, %d" % (d.eid, nd))
        d.lines += ["*SPRING, ELSET=%s" % tag, "%d" % dof, "%.6f" % spring_k]
    d.lines += contact_lines(k_contact)
    pairs = []
    for j in range(ny):
        for i in range(nx):
            k = j * nx + i
            if i + 1 < nx:
                pairs.append(("SD%dE" % k, "SD%dW" % (k + 1)))
            if j + 1 < ny:
                pairs.append(("SD%dN" % k, "SD%dS" % (k + nx)))
            if i == 0:
                pairs.append(("SD%dW" % k, "SLEFT"))
            if i == nx - 1:
                pairs.append(("SD%dE" % k, "SRIGHT"))
            if j == 0:
                pairs.append(("SD%dS" % k, "SBOTTOM"))
            if j == ny - 1:
                pairs.append(("SD%dN" % k, "STOP"))
    d.lines.append(contact_pair())
    d.lines += ["%s, %s" % p for p in pairs]
    d.lines += ["*BOUNDARY", "LEFT, 2, 2", "RIGHT, 2, 2", "BOTTOM, 1, 2", "TOP, 1, 2"] + (["NALL, 3, 3"] if slab else [])
    if hold == "pins":
        d.lines += ["PINS, 2, 2"]
    travel = speed * (tend - t0)
    d.lines += ["*STEP, NLGEOM, INC=100000", "*STATIC", "%g, %.9g, 1e-9, %g" % (min(0.01, dtmax), tend - t0, dtmax)]
    if CONTROLS:
        d.lines += ["*CONTROLS, PARAMETERS=TIME INCREMENTATION", CONTROLS]
    d.lines += ["*BOUNDARY", "LEFT, 1, 1, %.9g" % travel, "RIGHT, 1, 1, %.9g" % (-travel)]
    for name in ("LEFT", "RIGHT", "BOTTOM", "TOP"):
        d.lines += ["*NODE PRINT, NSET=%s, TOTALS=ONLY, FREQUENCY=1" % name, "RF"]
    d.lines += ["*END STEP"]
    targets = DIE_TARGETS
    meta = {"job": "die%d" % nx, "code": "ccx", "n": n, "element": element, "k_contact": k_contact,
            "nodes": d.nid, "elements": len(centres) * len(disc.elems), "h": math.pi / 4 * r / n,
            "r": r, "width": width, "solid0": solid0, "speed": speed, "end": tend, "t0": t0,
            "times": die_times(nx, ny, width, solid0, targets, speed),
            "labels": ["%.2f" % t for t in targets]}
    return d.text(), meta


# ---------------------------------------------------------------------------------------
# mpfem cases

MATERIAL_TOML = """[[materials]]
name = "alu"
model = "j2"
youngs_modulus = 64100.0
poisson_ratio = 0.3
hardening = { preset = "aluminium_250c" }
"""


def mpfem_disc(h, dt, R=10.0, travel=3.0):
    text = f"""# peer benchmark: quarter aluminium disc between rigid frictionless plates, pressed to
# 30 % of its diameter (written by benches/peer/make_decks.py; mpfem's defaults otherwise)
title = "peer disc, h = {h}"

{MATERIAL_TOML}
[[bodies]]
name = "disc"
material = "alu"
mesh_size = {h}
shape = {{ type = "disc", center = [0.0, 0.0], radius = {R}, part = "quarter" }}

[[boundary]]
body = "disc"
set = "axis_y"
ux = 0.0

[[boundary]]
body = "disc"
set = "axis_x"
uy = 0.0

[[walls]]
side = "top"
position = {R}
travel = {travel}

[time]
end = 1.0
dt = {dt}
dt_max = {dt}

[output]
every = 0
"""
    meta = {"job": "disc", "code": "mpfem", "h": h, "dt": dt, "R": R, "travel": travel,
            "times": [1 / 3, 2 / 3, 1.0], "labels": ["10%", "20%", "30%"]}
    return text, meta


# mpfem's pinned die: each disc as two half discs (part = "half", the lower one turned by
# 180 degrees) whose cuts are held at u_y = 0 (the same constraint as CalculiX's PINS); the
# halves sit HALF_GAP * r off the disc's diameter each (the barrier needs a gap between them;
# both halves being pinned, the barrier between them, where within its reach, pushes only
# against their constraints; the disc is 0.1 % taller)
HALF_GAP = 1e-3


def mpfem_particles(nx, ny, h, width, solid0, hold):
    if hold != "pins":
        return f"""[[grids]]
material = "alu"
nx = {nx}
ny = {ny}
shape = "disc"
solid_ratio = {solid0}
mesh_size = {h}
"""
    r, centres = die_geometry(nx, ny, width, solid0)
    g = HALF_GAP * r
    out = []
    for k, (cx, cy) in enumerate(centres):
        for tag, dy, angle in (("u", g, 0.0), ("l", -g, 180.0)):
            name = "d%d%s" % (k, tag)
            out.append(f"""[[bodies]]
name = "{name}"
material = "alu"
mesh_size = {h}
shape = {{ type = "disc", center = [{cx:.12g}, {cy + dy:.12g}], radius = {r:.12g}, part = "half", angle = {angle:g} }}

[[boundary]]
body = "{name}"
set = "axis_x"
uy = 0.0
""")
    return "\n".join(out)


def mpfem_die(nx, ny, h, dt, dt_max, width=100.0, solid0=0.70, speed=10.0, end_solid=0.95, hold=HOLD):
    tend = die_times(nx, ny, width, solid0, [end_solid], speed)[0]
    particles = mpfem_particles(nx, ny, h, width, solid0, hold)
    text = f"""# peer benchmark: {nx} x {ny} aluminium discs in a {width:g} mm square die at solid ratio
# {solid0}, lateral compaction (left and right walls at {speed:g} mm/s), frictionless, to the
# nominal solid ratio {end_solid} (written by benches/peer/make_decks.py; mpfem's defaults otherwise)
title = "peer die {nx} x {ny}, h = {h}"

{MATERIAL_TOML}
[[walls]]
side = "left"
position = 0.0
velocity = {speed}

[[walls]]
side = "right"
position = {width}
velocity = {speed}

[[walls]]
side = "bottom"
position = 0.0

[[walls]]
side = "top"
position = {width}

{particles}
[time]
end = {tend:.9f}
dt = {dt}
dt_max = {dt_max}

[output]
every = 0
"""
    r, _ = die_geometry(nx, ny, width, solid0)
    meta = {"job": "die%d" % nx, "code": "mpfem", "h": h, "dt": dt, "dt_max": dt_max, "r": r,
            "width": width, "solid0": solid0, "speed": speed, "end": tend,
            "times": die_times(nx, ny, width, solid0, DIE_TARGETS, speed),
            "labels": ["%.2f" % t for t in DIE_TARGETS]}
    return text, meta


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--job", choices=["disc", "die2", "die4"], required=True)
    ap.add_argument("--ccx-n", type=int, help="CalculiX: elements on each 45 degree arc of a disc")
    ap.add_argument("--element", default="CPE4", help="CalculiX element (CPE4, CPE4R, CPE8R, CPE8, C3D8I, ...)")
    ap.add_argument("--k-contact", type=float, default=None, help="CalculiX contact slope K (MPa/mm)")
    ap.add_argument("--ccx-dtmax", type=float, default=None, help="CalculiX largest increment (s)")
    ap.add_argument("--mpfem-h", type=float, help="mpfem: mesh_size (mm)")
    ap.add_argument("--mpfem-dt", type=float, default=None, help="mpfem: dt (and dt_max on the disc)")
    ap.add_argument("--mpfem-dtmax", type=float, default=None, help="mpfem: dt_max (die jobs)")
    ap.add_argument("--name", default=None)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)

    def write(name, ext, text, meta):
        with open(os.path.join(a.out, name + ext), "w") as f:
            f.write(text)
        with open(os.path.join(a.out, name + ".json"), "w") as f:
            json.dump(meta, f, indent=1)

    if a.ccx_n:
        name = a.name or "%s_ccx_n%d" % (a.job, a.ccx_n)
        if a.job == "disc":
            k = a.k_contact or 10.0 * E
            text, meta = ccx_disc(a.ccx_n, a.element, k, dtmax=a.ccx_dtmax or 0.1)
        else:
            nx = int(a.job[3:])
            k = a.k_contact or 10.0 * E
            text, meta = ccx_die(nx, nx, a.ccx_n, a.element, k, a.ccx_dtmax or 0.02)
        write(name, ".inp", text, meta)
    if a.mpfem_h:
        name = a.name or "%s_mpfem_h%g" % (a.job, a.mpfem_h)
        if a.job == "disc":
            text, meta = mpfem_disc(a.mpfem_h, a.mpfem_dt or 1 / 6)
        else:
            nx = int(a.job[3:])
            text, meta = mpfem_die(nx, nx, a.mpfem_h, a.mpfem_dt or 0.02, a.mpfem_dtmax or 0.05)
        write(name, ".toml", text, meta)


if __name__ == "__main__":
    main()
