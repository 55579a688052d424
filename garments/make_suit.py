#!/usr/bin/env python3
"""Writes garments/nbc_suit.ron: a one-piece NBC coverall with attached hood for the
shipped mannequin (garments/body/measurements.ron, stature 1.76 m), dressed in the A-pose
garments/body/poses/a_pose.ron.

Every panel is placed `Around` a named arrangement point of the mannequin body
(`src/garment/arrange.rs`: cylinders round the limbs, elliptic shells round the trunk and
head, at a clearance), so no 3D coordinate is computed here. The script only drafts the
flat pattern from the body measurements (girths plus ease, lengths from the skeleton's
proportions in src/mannequin/skeleton.rs) and names which edge is sewn to which, so that
the two sides of every seam have the same length (checked below).

Conventions: outlines are counter-clockwise in pattern (u, v); u runs counter-clockwise
round the segment axis seen from its tip, v up the segment (towards the proximal joint;
for the trunk and hood: upwards). Every panel's director points away from the body, so two
panels meeting at a seam run along it in opposite directions: every seam has
`reversed: true` on its b side. Right-hand pieces are the mirror images (u → −u) of the
left-hand ones.

Usage: python3 garments/make_suit.py [OUT.ron] [--element-size H] [--discrete]
                                     [--protocol MOTION] [--side-back D]
                                     [--fine-underarm H] [--fine PREFIX H ...]
                                     [--gusset-depth D] [--seat-ease S] [--back-ease E]
(--protocol body/suit_motion.ron --fine-underarm 0.04 --fine sleeve_top_ 0.06 --fine
sleeve_under_fore_ 0.06: the mannequin moves through that motion file after the drape, one
step to rest per frame, with the under sleeves of the upper arms and the gussets meshed at
4 cm and the other sleeve pieces at 6 cm: garments/nbc_suit_protocol.ron.)
Movement ease (all 0 or the draft's own in garments/nbc_suit.ron): --gusset-depth D, the
underarm gusset D deep down the arm (0.06 m drafted); --seat-ease S, the back rise S longer at
the centre back (a seat wedge); --back-ease E, each back quarter E wider across the shoulder
blades (a centre back bulge). See the comments at each.
"""

import math
import os
import sys

H = 1.76  # stature (garments/body/measurements.ron)
UPPER_ARM = 0.56 * 0.59
FOREARM = 0.59 - UPPER_ARM
HIP_Z = 0.81 + 0.05 * H
KNEE_Z = 0.56 * HIP_Z
ANKLE_Z = 0.045 * H
LUMBAR_Z = 0.605 * H
HEAD_Z = 0.885 * H


class Panel:
    def __init__(self, name, outline, edges, point, anchor, along, clearance, grain=(0.0, 1.0)):
        self.name = name
        self.outline = [tuple(p) for p in outline]
        self.edges = dict(edges)  # name -> (from, to), vertex indices, counter-clockwise
        self.point = point
        self.anchor = anchor
        self.along = along
        self.clearance = clearance
        self.grain = grain

    def edge_length(self, edge):
        a, b = self.edges[edge]
        n = len(self.outline)
        length, k = 0.0, a
        while k != b:
            p, q = self.outline[k], self.outline[(k + 1) % n]
            length += math.hypot(q[0] - p[0], q[1] - p[1])
            k = (k + 1) % n
        return length

    def mirrored(self, name, point):
        """The mirror image u → −u (right-hand piece): vertex order reversed to stay
        counter-clockwise, every edge (a, b) becomes (b', a') with i' = n − 1 − i."""
        n = len(self.outline)
        outline = [(-u, v) for (u, v) in reversed(self.outline)]
        edges = {k: (n - 1 - b, n - 1 - a) for k, (a, b) in self.edges.items()}
        return Panel(name, outline, edges, point, (-self.anchor[0], self.anchor[1]), self.along, self.clearance, (-self.grain[0], self.grain[1]))


def f(x):
    return f"{x:.6f}".rstrip("0").rstrip(".") if abs(x) > 1e-12 else "0.0"


def pt(p):
    return f"({f(p[0])}, {f(p[1])})"


# ---------------------------------------------------------------------------------------
# Trunk: four quarters on the trunk shell (point torso.front / torso.back, v from the waist
# (lumbar joint) up), from below the crotch at the centre lines to the shoulders.
C_TRUNK = 0.03
W = 0.28                      # quarter width (hip girth 1.00 + 0.12 ease) / 4
VB = 0.82 - LUMBAR_Z          # bottom at the sides (the thigh pieces start 0.10 m below the hip)
CROTCH_DROP = 0.12            # the centre front/back runs down between the legs (rise)
UC = 0.08                     # crotch curve's width
ARMHOLE_DROP = 0.03           # the armpit this far below the body's (room under the arm)
VA = 1.29 - ARMHOLE_DROP - LUMBAR_Z  # armpit (top of the side seam)
UNDERARM = 0.06               # each half of the underarm gusset's top edge
# Neckline: a collar of 0.46 m round the neck (girth 0.39 m), its centre front at 1.465 m and
# centre back at 1.505 m (the jugular notch and the seventh vertebra's height with ease).
NECK_W = 0.09                 # neck opening half-width at the shoulder line
VNF = 0.40                    # neck point at the centre front
VNB = 0.44                    # neck point at the centre back
NECK_INNER = 0.05             # back neckline part sewn to the hood's back gusset

ua_dx = math.sqrt(UNDERARM ** 2 - 0.01 ** 2)
p_under = (W - ua_dx, VA + 0.01)
# The shoulder line. The quarters stand on the trunk's elliptic shell ~0.16 m in front of and
# behind the body's mid-plane, and the shoulder (flat-topped at 1.47-1.48 m, ±0.07-0.10 m
# deep) lies between them: each quarter needs a flap E_SH above the line it used to end at
# (1.448 m) to reach a shoulder seam on top of the shoulder without pulling the whole suit
# up (drawn without the flaps, the sewn suit was stretched 6-8 % along the trunk and lifted
# 4-7 cm). The armhole runs from the underarm straight up to the flap's outer corner.
VS = (1.29 - LUMBAR_Z) + 0.01 + math.sqrt(0.16 ** 2 - (0.10 - math.sqrt(0.04 ** 2 - 0.01 ** 2)) ** 2)
E_SH = 0.10                   # shoulder flaps: over the shoulder to a seam on its top
VS += E_SH
p_sh = (W - 0.06, VS)
ARMHOLE = math.hypot(p_sh[0] - p_under[0], p_sh[1] - p_under[1])  # each half of the sleeve cap


# Seam-layout variant (--side-back D, docs/compare_suit/): the side seam swept back by D at its
# bottom (the front quarters D wider at the leg seam, the back quarters D narrower; the armpit
# end unchanged), so that it leaves the line down the side of the trunk; the outer thigh
# pieces' top split moves with it (0 in garments/nbc_suit.ron).
# Under the arm (--fine-underarm H, garments/nbc_suit_protocol.ron): the under sleeves of the
# upper arms and the underarm gussets meshed at H instead of the garment's element size. When
# the arm moves against the trunk the under sleeve folds; at 0.1 m (67-79 mm elements) the fold
# forms inside one element (the laminate's bending length is 61.5 mm) and the solve stops.
# The same holds for the rest of the sleeve in the protocol: with the forearms' under sleeves
# at 0.1 m one folds through itself when the arms are lowered from the horizontal (after the
# trunk twist); with those at 6 cm, a forearm's top sleeve (62.6 mm elements) folds while the
# arms are raised; with every sleeve piece at 6 cm or finer the arms go up and down.
FINE_UNDERARM = float(sys.argv[sys.argv.index("--fine-underarm") + 1]) if "--fine-underarm" in sys.argv else 0.0
# Finer pieces elsewhere (--fine PREFIX H, repeatable): every panel whose name starts with
# PREFIX (e.g. sleeve_under_fore_) meshed at H.
FINE = [(sys.argv[i + 1], float(sys.argv[i + 2])) for i, a in enumerate(sys.argv) if a == "--fine"]
if FINE_UNDERARM:
    FINE = [("sleeve_under_upper_", FINE_UNDERARM), ("gusset_", FINE_UNDERARM)] + FINE
SIDE_BACK = float(sys.argv[sys.argv.index("--side-back") + 1]) if "--side-back" in sys.argv else 0.0
# Sub-element buckling (--compression F, off in garments/nbc_suit.ron): every ply's fabric gets
# compression_table [(0, 1), (0.001, F)], its membrane stiffness under compression scaled to F
# past 0.1 % compressive strain (README "Fabric, contact and drape"). The 0.1 m suit's elements
# are larger than the laminate's bending length (61.5 mm): fabric bunched between chest and arm
# in the arms-forward pose has to fold inside one element without it.
COMPRESSION = float(sys.argv[sys.argv.index("--compression") + 1]) if "--compression" in sys.argv else 0.0
# Reach ease across the back (--back-ease E, 0 in garments/nbc_suit.ron): each back quarter's
# centre back bulges out by E between the waist and the neck (flat at E over the shoulder
# blades, V_BLADE), so the back is 2E wider across the blades than the body's quarters while
# every other edge (side, armhole, shoulder, neck) keeps its length. The arms swung forward
# 90° carry the back armhole seams ~0.1 m forward round the trunk; the skin across the back
# stretches 13-16 % in that reach (Kirk & Ibrahim, Text. Res. J. 36, 1966), ≈ 5-6 cm of the
# ≈ 0.38 m across-back width, and a coverall's bi-swing back or action pleats give it that room.
# The back quarters are placed E/2 further round towards the sides, so that the two bulges do
# not cross the centre line (placed crossing, the sewing crawled: Δt ~ 4e-5 s from the start).
# Measured (A-pose → arms forward in 1 s, README "The NBC suit in motion"): E = 0.02 sews and
# gets to 71 % of the arms forward (53 % without); E = 0.03 and 0.04 no longer sew (the right
# back shoulder corner and the top sleeve's crown fold at t = 0.27 s of the 0.3 s closure).
BACK_EASE = float(sys.argv[sys.argv.index("--back-ease") + 1]) if "--back-ease" in sys.argv else 0.0
V_BLADE = (0.22, 0.36)        # the bulge's flat part (shoulder blades, v above the waist)
V_BULGE = (0.06, VNB)         # where it starts (at the waist) and ends (centre back neck)
# Seat ease (--seat-ease S, 0 in garments/nbc_suit.ron): a longer back rise. Each back quarter
# is slashed across at the hip joint's height (V_SEAT) from the centre back to the side seam
# and its lower part (seat and crotch) turned about the side point, so that the centre back
# gains S, tapering to nothing at the side, while every seam keeps its length (the side edge
# kinks at the hinge; the crotch and leg edges turn with the seat). A hip flexed by θ lengthens
# the back over the seat by about d·θ, d the seat's distance behind the hip's flexion axis
# (≈ 0.1 m, 0 at the side where the axis comes out): 100° of flexion in the deep squat ≈ 0.17
# m at the centre back, a straight-legged stride or the A-pose nothing — the same wedge
# (nothing at the side, most at the centre back) a trouser pattern's seat angle adds.
SEAT_EASE = float(sys.argv[sys.argv.index("--seat-ease") + 1]) if "--seat-ease" in sys.argv else 0.0
V_SEAT = HIP_Z - LUMBAR_Z     # the slash: the hip joints' height above the waist (-0.167 m)


def trunk_left(front):
    """front_l (CF at u = 0, side at u = W) or back_l mirrored later; returns the panel for
    the left front quarter when `front`, else the left back quarter drawn with CB at u = 0
    (mirrored to put the side at u = 0)."""
    vn = VNF if front else VNB
    w_hem = W + SIDE_BACK if front else W - SIDE_BACK
    outline = [
        (0.0, VB - CROTCH_DROP),            # 0 centre line, bottom of the crotch curve
        (0.05, VB - 0.02),                  # 1
        (UC, VB),                           # 2 crotch / leg split
        (w_hem, VB),                        # 3 side bottom
        (W, VA),                            # 4 armpit
        p_under,                            # 5 underarm / armhole
        p_sh,                               # 6 shoulder point
        (NECK_W, VS),                       # 7 neck at the shoulder line
    ]
    edges = {"crotch": (0, 2), "leg": (2, 3), "side": (3, 4), "underarm": (4, 5), "armhole": (5, 6), "shoulder": (6, 7)}
    if front:
        outline += [(0.0, vn)]              # 8 centre front neck
        edges.update({"neck": (7, 8), "centre": (8, 0)})
        return outline, edges
    outline += [(NECK_INNER, vn), (0.0, vn)]  # 8, 9
    edges.update({"neck_outer": (7, 8), "neck_inner": (8, 9), "centre": (9, 0)})
    if BACK_EASE:
        # the centre back bulge and its start at the waist
        outline += [(-BACK_EASE, V_BLADE[1]), (-BACK_EASE, V_BLADE[0]), (0.0, V_BULGE[0])]
    if SEAT_EASE:
        # the seat wedge: points 0-3 turned about the side point at V_SEAT (the hinge, inserted
        # after them) by the angle whose chord at the centre line is SEAT_EASE; the centre
        # line's slash point and its turned image end the outline (the wedge between them)
        hinge = (w_hem + (W - w_hem) * (V_SEAT - VB) / (VA - VB), V_SEAT)
        a = 2.0 * math.asin(SEAT_EASE / (2.0 * hinge[0]))
        c, s_ = math.cos(a), math.sin(a)
        turn = lambda p: (hinge[0] + c * (p[0] - hinge[0]) - s_ * (p[1] - hinge[1]), hinge[1] + s_ * (p[0] - hinge[0]) + c * (p[1] - hinge[1]))
        outline = [turn(p) for p in outline[:4]] + [hinge] + outline[4:] + [(0.0, V_SEAT), turn((0.0, V_SEAT))]
        edges = {k: (i + (i >= 4), j + (j >= 4)) for k, (i, j) in edges.items()}
        edges["side"] = (3, 5)
        edges["centre"] = (10, 0)
    return outline, edges


fl_outline, fl_edges = trunk_left(True)
# front_l: CF 1 cm left of the front point, running counter-clockwise (to the body's left).
front_l = Panel("front_l", fl_outline, fl_edges, "torso.front", (-0.01, 0.0), 0.0, C_TRUNK)
front_r = front_l.mirrored("front_r", "torso.front")
bl_outline, bl_edges = trunk_left(False)
# The back quarters: back_r runs counter-clockwise from 1 cm right of the back point to the
# right side; drawn as the left-front shape (CB at u = 0), so back_r is that shape and
# back_l its mirror.
back_r = Panel("back_r", bl_outline, bl_edges, "torso.back", (-0.01 - BACK_EASE / 2, 0.0), 0.0, C_TRUNK)
back_l = back_r.mirrored("back_l", "torso.back")

# ---------------------------------------------------------------------------------------
# Sleeves (left; the right ones mirrored): top sleeve round the outside, under sleeve and
# underarm gusset round the inside of the upper arm, top and under sleeve of the forearm,
# cuff. Upper arm: v from the shoulder joint (negative down the arm).
C_ARM = 0.025
V_CAP = -0.11
# The underarm gusset's depth down the arm (--gusset-depth D, 0.06 m in garments/nbc_suit.ron):
# the top sleeve's high sides and the gusset's sides grow with it, the under sleeve and the
# top sleeve's low sides shrink, every seam keeping its length. It adds no fabric (the sleeve's
# girth at every level stays TOP_CAP + GUS_TOP): the gusset reaches further down the front and
# back of the armpit, where the fabric folds as the arm swings forward, and with
# --fine-underarm it is the finer-meshed piece there instead of the top sleeve.
GUSSET_DEPTH = float(sys.argv[sys.argv.index("--gusset-depth") + 1]) if "--gusset-depth" in sys.argv else 0.06
V_GUS = V_CAP - GUSSET_DEPTH
V_EL = -(UPPER_ARM - 0.02)
TOP_CAP = 0.365               # top sleeve's cap base width (with the gusset's top: 0.485 m round)
# The cap: each half a steep segment up from the cap base and a shallow one (CROWN_SLOPE
# from the horizontal, CROWN_W wide) to the crown, so that each half is as long as its
# armhole (0.278 m) and the crown is blunt: 130°, where it meets the two shoulder flaps'
# 90° corners. A pointed crown (one straight segment per half, 75°) folded its corner
# element at the end of the sewing and again at rest.
CROWN_W, CROWN_SLOPE = 0.08, math.radians(25.0)
crown_len = CROWN_W / math.cos(CROWN_SLOPE)
CAP_H = CROWN_W * math.tan(CROWN_SLOPE) + math.sqrt((ARMHOLE - crown_len) ** 2 - (TOP_CAP / 2 - CROWN_W) ** 2)
UNDER_W = 0.19                # under sleeve / gusset bottom
GUS_TOP = 2 * UNDERARM
TOP_W = TOP_CAP - UNDER_W + GUS_TOP  # top sleeve below the gusset (its sides as long as the gusset's)
s = (TOP_CAP - TOP_W) / 2
top_upper = Panel("sleeve_top_upper_l", [
    (s, V_EL), (s + TOP_W, V_EL), (s + TOP_W, V_GUS), (TOP_CAP, V_CAP),
    (TOP_CAP / 2 + CROWN_W, V_CAP + CAP_H - CROWN_W * math.tan(CROWN_SLOPE)), (TOP_CAP / 2, V_CAP + CAP_H),
    (TOP_CAP / 2 - CROWN_W, V_CAP + CAP_H - CROWN_W * math.tan(CROWN_SLOPE)), (0.0, V_CAP), (s, V_GUS),
], {"elbow": (0, 1), "back_low": (1, 2), "back_high": (2, 3), "cap_back": (3, 5), "cap_front": (5, 7), "front_high": (7, 8), "front_low": (8, 0)},
    "upper_arm_l.outer", (TOP_CAP / 2, 0.0), 0.0, C_ARM)
g = (UNDER_W - GUS_TOP) / 2
gusset = Panel("gusset_l", [
    (0.0, V_GUS), (UNDER_W, V_GUS), (UNDER_W - g, V_CAP), (UNDER_W / 2, V_CAP), (g, V_CAP),
], {"bottom": (0, 1), "front": (1, 2), "top_front": (2, 3), "top_back": (3, 4), "back": (4, 0)},
    "upper_arm_l.inner", (UNDER_W / 2, 0.0), 0.0, C_ARM)
under_upper = Panel("sleeve_under_upper_l", [
    (0.0, V_EL), (UNDER_W, V_EL), (UNDER_W, V_GUS), (0.0, V_GUS),
], {"elbow": (0, 1), "front": (1, 2), "top": (2, 3), "back": (3, 0)},
    "upper_arm_l.inner", (UNDER_W / 2, 0.0), 0.0, C_ARM)
# Forearm: v from the elbow joint.
C_FORE = 0.03
VF_TOP = -0.01
VF_BOT = -0.20
UNDER_WRIST = 0.14
TOP_WRIST = TOP_W - UNDER_W + UNDER_WRIST  # equal tapers: the forearm seams' sides agree
d = (TOP_W - TOP_WRIST) / 2
top_fore = Panel("sleeve_top_fore_l", [
    (d, VF_BOT), (d + TOP_WRIST / 2, VF_BOT), (d + TOP_WRIST, VF_BOT), (TOP_W, VF_TOP), (0.0, VF_TOP),
], {"cuff_front": (0, 1), "cuff_back": (1, 2), "back": (2, 3), "elbow": (3, 4), "front": (4, 0)},
    "forearm_l.outer", (TOP_W / 2, 0.0), 0.0, C_FORE)
d = (UNDER_W - UNDER_WRIST) / 2
under_fore = Panel("sleeve_under_fore_l", [
    (d, VF_BOT), (d + UNDER_WRIST, VF_BOT), (UNDER_W, VF_TOP), (0.0, VF_TOP),
], {"cuff": (0, 1), "front": (1, 2), "elbow": (2, 3), "back": (3, 0)},
    "forearm_l.inner", (UNDER_W / 2, 0.0), 0.0, C_FORE)
VC_TOP, VC_BOT = VF_BOT - 0.01, VF_BOT - 0.06
CUFF = TOP_WRIST + UNDER_WRIST
# The cuff: one band round the wrist, centred on the inside, closed on the outside; its top
# edge: the under sleeve's part in the middle, the top sleeve's in two halves at the ends.
q = TOP_WRIST / 2
cuff = Panel("cuff_l", [
    (0.0, VC_BOT), (CUFF, VC_BOT), (CUFF, VC_TOP), (CUFF - q, VC_TOP), (q, VC_TOP), (0.0, VC_TOP),
], {"end_a": (1, 2), "top_front": (2, 3), "top_under": (3, 4), "top_back": (4, 5), "end_b": (5, 0)},
    "forearm_l.inner", (CUFF / 2, 0.0), 0.0, 0.02)

# ---------------------------------------------------------------------------------------
# Legs (left; right mirrored): outer and inner thigh pieces, outer and inner shank pieces,
# ankle cuff. Thigh: v from the hip joint.
C_LEG = 0.025
VT_TOP = -0.10
VT_BOT = -(HIP_Z - KNEE_Z) + 0.015
crotch_len = front_l.edge_length("crotch")
leg_len = front_l.edge_length("leg")
leg_len_back = back_l.edge_length("leg")
OUT_TOP, IN_TOP = leg_len + leg_len_back, 2 * crotch_len
OUT_KNEE, IN_KNEE = OUT_TOP - 0.12, IN_TOP - 0.12   # equal tapers: equal seam lengths
d = (OUT_TOP - OUT_KNEE) / 2
thigh_outer = Panel("thigh_outer_l", [
    (d, VT_BOT), (d + OUT_KNEE, VT_BOT), (OUT_TOP, VT_TOP), (leg_len, VT_TOP), (0.0, VT_TOP),
], {"knee": (0, 1), "back": (1, 2), "top_back": (2, 3), "top_front": (3, 4), "front": (4, 0)},
    "thigh_l.outer", (OUT_TOP / 2, 0.0), 0.0, C_LEG)
d = (IN_TOP - IN_KNEE) / 2
thigh_inner = Panel("thigh_inner_l", [
    (d, VT_BOT), (d + IN_KNEE, VT_BOT), (IN_TOP, VT_TOP), (IN_TOP / 2, VT_TOP), (0.0, VT_TOP),
], {"knee": (0, 1), "front": (1, 2), "top_front": (2, 3), "top_back": (3, 4), "back": (4, 0)},
    "thigh_l.inner", (IN_TOP / 2, 0.0), 0.0, C_LEG)
# Shank: v from the knee joint.
VS_TOP = -0.01
VS_BOT = -(KNEE_Z - ANKLE_Z) + 0.10
OUT_ANK, IN_ANK = OUT_KNEE - 0.05, IN_KNEE - 0.05
d = (OUT_KNEE - OUT_ANK) / 2
shank_outer = Panel("shank_outer_l", [
    (d, VS_BOT), (d + OUT_ANK / 2, VS_BOT), (d + OUT_ANK, VS_BOT), (OUT_KNEE, VS_TOP), (0.0, VS_TOP),
], {"ankle_front": (0, 1), "ankle_back": (1, 2), "back": (2, 3), "knee": (3, 4), "front": (4, 0)},
    "shank_l.outer", (OUT_KNEE / 2, 0.0), 0.0, C_LEG)
d = (IN_KNEE - IN_ANK) / 2
shank_inner = Panel("shank_inner_l", [
    (d, VS_BOT), (d + IN_ANK, VS_BOT), (IN_KNEE, VS_TOP), (0.0, VS_TOP),
], {"ankle": (0, 1), "front": (1, 2), "knee": (2, 3), "back": (3, 0)},
    "shank_l.inner", (IN_KNEE / 2, 0.0), 0.0, C_LEG)
VA_TOP, VA_BOT = VS_BOT - 0.01, VS_BOT - 0.06
ANK = OUT_ANK + IN_ANK
q = OUT_ANK / 2
ankle = Panel("ankle_cuff_l", [
    (0.0, VA_BOT), (ANK, VA_BOT), (ANK, VA_TOP), (ANK - q, VA_TOP), (q, VA_TOP), (0.0, VA_TOP),
], {"end_a": (1, 2), "top_front": (2, 3), "top_inner": (3, 4), "top_back": (4, 5), "end_b": (5, 0)},
    "shank_l.inner", (ANK / 2, 0.0), 0.0, 0.02)

# ---------------------------------------------------------------------------------------
# Hood: left and right sides and a back gusset on the head shell (v from the head joint),
# the sides anchored at the back so the gaps to the gusset are small; crown and upper back
# seams close over the head; the neck edge is sewn to the trunk's neckline.
C_HOOD = 0.03
HV_BOT = 1.51 - HEAD_Z
HV_TOP = 1.85 - HEAD_Z
GUS_HALF = 0.05
HV_GUS = 1.66 - HEAD_Z
hood_back = Panel("hood_back", [
    (0.0, HV_BOT), (GUS_HALF, HV_BOT), (2 * GUS_HALF, HV_BOT), (2 * GUS_HALF, HV_GUS), (GUS_HALF, HV_GUS + 0.04), (0.0, HV_GUS),
], {"bottom_l": (0, 1), "bottom_r": (1, 2), "side_r": (2, 4), "side_l": (4, 0)},
    "head.back", (GUS_HALF, 0.0), 0.0, C_HOOD)
side_len = hood_back.edge_length("side_l")
neck_front = front_l.edge_length("neck")
neck_back = back_l.edge_length("neck_outer")
HOOD_W = neck_front + neck_back + 0.04
# The hood sides sit this far forward of the back gusset (gaps of up to 0.12 m there to sew):
# the head's shell is ~0.8 m round, the hood 0.54 m, and with the sides placed against the
# gusset their neck corners started at the sides of the head and crossed the front quarters'
# neck flaps on their way to the centre front (the two panels' prisms overlapped there for
# ten time steps of the sewing).
HOOD_FORWARD = 0.06
u0 = HOOD_W - neck_front - neck_back
hood_l = Panel("hood_l", [
    (u0, HV_BOT), (u0 + neck_front, HV_BOT), (HOOD_W, HV_BOT), (HOOD_W, HV_BOT + side_len),
    (HOOD_W - 0.04, HV_TOP), (0.02, HV_TOP), (0.0, 0.05),
], {"neck_front": (0, 1), "neck_back": (1, 2), "back_low": (2, 3), "back_high": (3, 4), "crown": (4, 5)},
    "head.back", (HOOD_W + 0.015 + GUS_HALF + HOOD_FORWARD, 0.0), 0.0, C_HOOD)
hood_r = hood_l.mirrored("hood_r", "head.back")

left = [top_upper, gusset, under_upper, top_fore, under_fore, cuff, thigh_outer, thigh_inner, shank_outer, shank_inner, ankle]
right = [p.mirrored(p.name[:-2] + "_r", p.point.replace("_l.", "_r.")) for p in left]
panels = [front_l, front_r, back_l, back_r] + left + right + [hood_l, hood_r, hood_back]
by_name = {p.name: p for p in panels}

# ---------------------------------------------------------------------------------------
# Seams: (name, a panel, a edge, b panel, b edge, kind). Kinds as on a real NBC suit: every
# outer seam sealed — taped (stitched and covered by a sealing tape) on the body, sleeves and
# legs; hood seams welded (bonded); cuffs welded to the sleeve and leg ends; gussets and the
# inner seams of the sleeves plain (under the arm, stitched only).
TAPE = "Taped(width: 0.02, stiffness_factor: 3.0)"
seams = [
    ("centre_front", "front_l", "centre", "front_r", "centre", TAPE),
    ("centre_back", "back_r", "centre", "back_l", "centre", TAPE),
    ("side_l", "front_l", "side", "back_l", "side", TAPE),
    ("side_r", "back_r", "side", "front_r", "side", TAPE),
    ("shoulder_l", "front_l", "shoulder", "back_l", "shoulder", TAPE),
    ("shoulder_r", "back_r", "shoulder", "front_r", "shoulder", TAPE),
    ("crown", "hood_l", "crown", "hood_r", "crown", "Welded"),
    ("hood_back_high", "hood_l", "back_high", "hood_r", "back_high", "Welded"),
    ("hood_gusset_l", "hood_back", "side_l", "hood_l", "back_low", "Welded"),
    ("hood_gusset_r", "hood_back", "side_r", "hood_r", "back_low", "Welded"),
    ("neck_front_l", "front_l", "neck", "hood_l", "neck_front", TAPE),
    ("neck_front_r", "front_r", "neck", "hood_r", "neck_front", TAPE),
    ("neck_back_l", "back_l", "neck_outer", "hood_l", "neck_back", TAPE),
    ("neck_back_r", "back_r", "neck_outer", "hood_r", "neck_back", TAPE),
    ("neck_gusset_l", "back_l", "neck_inner", "hood_back", "bottom_l", TAPE),
    ("neck_gusset_r", "back_r", "neck_inner", "hood_back", "bottom_r", TAPE),
]
for s in ("l", "r"):
    top, gus, und = f"sleeve_top_upper_{s}", f"gusset_{s}", f"sleeve_under_upper_{s}"
    tf, uf, cf = f"sleeve_top_fore_{s}", f"sleeve_under_fore_{s}", f"cuff_{s}"
    fr, bk = f"front_{s}", f"back_{s}"
    seams += [
        (f"armhole_front_{s}", fr, "armhole", top, "cap_front", TAPE),
        (f"armhole_back_{s}", bk, "armhole", top, "cap_back", TAPE),
        (f"underarm_front_{s}", fr, "underarm", gus, "top_front", "Plain"),
        (f"underarm_back_{s}", bk, "underarm", gus, "top_back", "Plain"),
        (f"gusset_front_{s}", top, "front_high", gus, "front", "Plain"),
        (f"gusset_back_{s}", top, "back_high", gus, "back", "Plain"),
        (f"gusset_bottom_{s}", gus, "bottom", und, "top", "Plain"),
        (f"sleeve_front_{s}", top, "front_low", und, "front", TAPE),
        (f"sleeve_back_{s}", top, "back_low", und, "back", TAPE),
        (f"elbow_top_{s}", top, "elbow", tf, "elbow", TAPE),
        (f"elbow_under_{s}", und, "elbow", uf, "elbow", TAPE),
        (f"forearm_front_{s}", tf, "front", uf, "front", TAPE),
        (f"forearm_back_{s}", tf, "back", uf, "back", TAPE),
        (f"cuff_under_{s}", uf, "cuff", cf, "top_under", "Welded"),
        (f"cuff_top_front_{s}", tf, "cuff_front", cf, "top_front", "Welded"),
        (f"cuff_top_back_{s}", tf, "cuff_back", cf, "top_back", "Welded"),
        (f"cuff_close_{s}", cf, "end_a", cf, "end_b", "Welded"),
    ]
    to, ti, so, si, ak = f"thigh_outer_{s}", f"thigh_inner_{s}", f"shank_outer_{s}", f"shank_inner_{s}", f"ankle_cuff_{s}"
    seams += [
        (f"leg_front_{s}", fr, "leg", to, "top_front", TAPE),
        (f"leg_back_{s}", bk, "leg", to, "top_back", TAPE),
        (f"crotch_front_{s}", fr, "crotch", ti, "top_front", TAPE),
        (f"crotch_back_{s}", bk, "crotch", ti, "top_back", TAPE),
        (f"thigh_front_{s}", to, "front", ti, "front", TAPE),
        (f"thigh_back_{s}", to, "back", ti, "back", TAPE),
        (f"knee_outer_{s}", to, "knee", so, "knee", TAPE),
        (f"knee_inner_{s}", ti, "knee", si, "knee", TAPE),
        (f"shank_front_{s}", so, "front", si, "front", TAPE),
        (f"shank_back_{s}", so, "back", si, "back", TAPE),
        (f"ankle_inner_{s}", si, "ankle", ak, "top_inner", "Welded"),
        (f"ankle_outer_front_{s}", so, "ankle_front", ak, "top_front", "Welded"),
        (f"ankle_outer_back_{s}", so, "ankle_back", ak, "top_back", "Welded"),
        (f"ankle_close_{s}", ak, "end_a", ak, "end_b", "Welded"),
    ]

# Quilting: the carbon layer is held to the shell and liner by stitch lines across the large
# panels (horizontal lines on the trunk quarters, one down each thigh piece); they tie the
# plies in the discrete model and vanish in the laminate.
quilting = []
for p in (front_l, front_r, back_l, back_r):
    us = [u for u, v in p.outline if not (abs(abs(u) - BACK_EASE) < 1e-12 and V_BLADE[0] <= v <= V_BLADE[1])]
    lo, hi = min(us), max(us)
    for k, v in enumerate((VB + 0.12, VB + 0.30)):
        quilting.append((f"quilt_{p.name}_{k + 1}", p.name, [(lo + 0.03, v), (hi - 0.03, v)]))
for s_ in ("l", "r"):
    for piece in (f"thigh_outer_{s_}", f"thigh_inner_{s_}"):
        p = by_name[piece]
        us = [u for u, _ in p.outline]
        mid = 0.5 * (min(us) + max(us))
        quilting.append((f"quilt_{piece}", piece, [(mid, VT_BOT + 0.04), (mid, VT_TOP - 0.04)]))


def check_lengths():
    """Both sides of every seam have the same length (1e-9 m: drafted equal)."""
    for name, a, ea, b, eb, _ in seams:
        la, lb = by_name[a].edge_length(ea), by_name[b].edge_length(eb)
        if abs(la - lb) > 1e-9:
            raise SystemExit(f"seam {name}: {a}.{ea} is {la:.4f} m, {b}.{eb} is {lb:.4f} m")


def ron(element_size, discrete, protocol=None, name="nbc_suit", body="body"):
    out = []
    w = out.append
    w("// GENERATED by garments/make_suit.py — edit the script, not this file.")
    w("//")
    w("// A one-piece NBC coverall with attached hood for the shipped mannequin")
    w("// (garments/body/measurements.ron, stature 1.76 m) in the A-pose (garments/body/poses/")
    w(f"// a_pose.ron): {len(panels)} panels (four trunk quarters; per arm a two-piece sleeve — top and")
    w("// under sleeve of the upper arm and forearm —, an underarm gusset and a cuff; per leg outer and")
    w("// inner thigh and shank pieces and an ankle cuff; a three-piece hood), "
      f"{len(seams)} seams (taped on")
    w("// the body, sleeves and legs, welded on the hood and cuffs, plain under the arms), three")
    w("// plies as in garments/nbc_hood.ron (ripstop outer shell, carbon adsorbent layer, knit liner),")
    w("// quilting lines on the trunk and thighs. Every panel is placed Around a named arrangement")
    w("// point of the mannequin body (cylinders round the limbs, elliptic shells round the trunk and")
    w("// head, a few cm off the body), sewn shut by virtual sewing (every seam closes with the")
    w("// `sew` closure over the first 0.3 s) under gravity, then left to come to rest on the body")
    w("// with barrier contact and friction.")
    w("//")
    if discrete:
        w("// Ply model: Discrete — one shell per ply, joined at the seams and quilting lines, with")
        w("// inter-ply and self contact (slow: see tests/nbc_suit.rs).")
    else:
        w("// Ply model: Laminate — the coarse default: each panel is one shell whose section stacks the")
        w("// three plies (classical lamination theory); the quilting lines vanish. Switch to the")
        w("// discrete three-ply model with `ply_model: Discrete` (or `python3 garments/make_suit.py")
        w("// OUT.ron --discrete`).")
    if FINE_UNDERARM:
        w(f"// Under the arm: the under sleeves of the upper arms and the gussets meshed at {f(FINE_UNDERARM)} m (--fine-underarm).")
    for prefix, h in FINE[2 if FINE_UNDERARM else 0:]:
        w(f"// Meshed at {f(h)} m: the panels {prefix}* (--fine {prefix} {f(h)}).")
    if SIDE_BACK != 0.0:
        w(f"// Seam layout: the trunk's side seams swept back {f(SIDE_BACK)} m at their bottom (--side-back).")
    if GUSSET_DEPTH != 0.06:
        w(f"// Underarm gussets {f(GUSSET_DEPTH)} m deep down the arm (--gusset-depth; drafted 0.06 m).")
    if SEAT_EASE:
        w(f"// Seat ease: the back rise {f(SEAT_EASE)} m longer at the centre back, a seat wedge (--seat-ease).")
    if BACK_EASE:
        w(f"// Reach ease: each back quarter {f(BACK_EASE)} m wider across the shoulder blades (--back-ease).")
    if COMPRESSION:
        w(f"// Sub-element buckling: each ply's membrane stiffness under compression scaled to {COMPRESSION} past 0.1 % strain (--compression).")
    w(f"// Element size {element_size} m (coarse).")
    w("Scene(")
    w(f'    name: "{name}",')
    w(f'    description: "NBC coverall with hood: {len(panels)} panels, {len(seams)} seams, 3 plies; placed round the mannequin, sewn, draped to rest",')
    w("    materials: {")
    ct = f", compression_table: Some([(0.0, 1.0), (0.001, {COMPRESSION})])" if COMPRESSION else ""
    w(f'        "ripstop": Fabric((preset: Some("ripstop"){ct})),')
    w('        "carbon_layer": Fabric((warp_tensile: Some(1500.0), weft_tensile: Some(1200.0), shear: Some(5.0), poisson: Some(0.2),')
    w(f"                                warp_bending: Some(2.0e-5), weft_bending: Some(1.6e-5), areal_density: Some(0.25), thickness: Some(0.0015){ct})),")
    w(f'        "liner": Fabric((preset: Some("knit_liner"){ct})),')
    w("    },")
    w("    parts: [],")
    w("    garment: Some((")
    w(f"        element_size: {element_size},")
    w(f"        ply_model: {'Discrete' if discrete else 'Laminate'},")
    w("        plies: {")
    w('            "outer": (material: "ripstop", thickness: 0.00035, areal_density: 0.20),')
    w('            "carbon": (material: "carbon_layer", thickness: 0.0015, areal_density: 0.25),')
    w('            "liner": (material: "liner", thickness: 0.0006, areal_density: 0.15),')
    w("        },")
    w("        panels: [")
    for p in panels:
        edges = ", ".join(f'"{k}": (from: {a}, to: {b})' for k, (a, b) in p.edges.items())
        w("            (")
        w(f'                name: "{p.name}",')
        sizes = [h for prefix, h in FINE if p.name.startswith(prefix)]
        if sizes:
            w(f"                element_size: Some({f(sizes[-1])}),")
        w(f"                outline: [{', '.join(pt(q) for q in p.outline)}],")
        w(f"                edges: {{{edges}}},")
        w(f"                grain: {pt(p.grain)},")
        w('                plies: ["outer", "carbon", "liner"],')
        w(f'                placement: Around(body: "body", point: "{p.point}", clearance: {f(p.clearance)}, anchor: {pt(p.anchor)}, along: {f(p.along)}),')
        w("            ),")
    w("        ],")
    w("        seams: [")
    for name, a, ea, b, eb, kind in seams:
        w(f'            (name: "{name}", a: (panel: "{a}", edge: "{ea}"), b: (panel: "{b}", edge: "{eb}", reversed: true), kind: {kind}, allowance: 0.01, stitch_spacing: 0.003, closing: Some("sew")),')
    w("        ],")
    w("        stitch_lines: [")
    for name, panel, pts in quilting:
        w(f'            (name: "{name}", panel: "{panel}", points: [{", ".join(pt(q) for q in pts)}]),')
    w("        ],")
    w("    )),")
    w("    loads: {")
    w('        "sew": Closure,')
    w('        "weight": GarmentWeight(g: (0.0, 0.0, -9.81)),')
    w("    },")
    w("    steps: [")
    w('        (name: "sew", increments: 1, scale: {"sew": 1.0, "weight": 1.0}, kind: Dynamic((ramp_time: 0.3))),')
    w("    ],")
    w("    contact: Some((formulation: Barrier(),")
    w("        bodies: [")
    if protocol is None:
        w(f'            (name: "body", shape: Mannequin(measurements: "{body}/measurements.ron", pose: Some("{body}/poses/a_pose.ron")), friction: 0.3),')
    else:
        w(f'            (name: "body", shape: Mannequin(measurements: "{body}/measurements.ron", motion: Some("{protocol}")), friction: 0.3),')
    w("        ],")
    w("    )),")
    if protocol is not None:
        w("    // Movement protocol: after the sewing and drape (body held in the motion's first frame, the")
        w("    // A-pose), one Dynamic step to rest per further frame (src/scene/protocol.rs).")
        w("    // Settling: mass-proportional damping 40/s and Δt ≤ 0.02 s (the body moves at most 2 % of")
        w("    // a pose change per time step); undamped with Δt ≤ 0.05 s the trunk twist stalled at 2.6°.")
        w('    protocol: Some((body: "body", settle: (dt: 1.0e-3, dt_max: 0.02, mass_damping: 40.0, max_steps: 4000))),')
    w(")")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    args = sys.argv[1:]
    element_size = 0.1
    if "--element-size" in args:
        i = args.index("--element-size")
        element_size = float(args[i + 1])
        del args[i:i + 2]
    discrete = "--discrete" in args
    args = [a for a in args if a != "--discrete"]
    for flag in ("--side-back", "--fine-underarm", "--back-ease", "--gusset-depth", "--seat-ease", "--compression"):
        if flag in args:
            i = args.index(flag)
            del args[i:i + 2]
    while "--fine" in args:
        i = args.index("--fine")
        del args[i:i + 3]
    protocol = None
    if "--protocol" in args:
        i = args.index("--protocol")
        protocol = args[i + 1]
        del args[i:i + 2]
    out = args[0] if args else "garments/nbc_suit.ron"
    check_lengths()
    with open(out, "w") as fh:
        # garments/body relative to the scene file (paths in a scene are relative to it).
        body = os.path.relpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "body"), os.path.dirname(os.path.abspath(out)))
        fh.write(ron(element_size, discrete, protocol, os.path.splitext(os.path.basename(out))[0], body))
    print(f"{out}: {len(panels)} panels, {len(seams)} seams, {len(quilting)} quilting lines")
