"""Approximate physical properties of each material family (SPEC §2), for export and physics.

A structure only names a family per part ("Wood", "Metal", ...); exporters and the physics
checks need a density (mass = mesh volume × density), a friction coefficient and a display
colour. Values are typical room-temperature handbook figures for the material a household
object of that family is usually made of (Engineering ToolBox / CRC Handbook ranges):

=========  =================  ==================================================  ==========
family     density (kg/m³)    typical range and the material taken                friction μ
=========  =================  ==================================================  ==========
Wood       700                softwoods 350–600, oak/beech 650–900; oak-like       0.45
                              (wood on wood, dry: 0.25–0.5)
Metal      7850               mild/stainless steel 7750–8050 (aluminium 2700)      0.6
                              (steel on steel, dry: 0.5–0.8)
Plastic    1050               ABS 1040–1070, PP 900, PVC 1380                      0.35
                              (plastic on plastic: 0.2–0.4)
Glass      2500               soda-lime glass 2400–2600                            0.9
                              (glass on glass, clean dry: 0.9–1.0)
Fabric     250                padded upholstery (foam core 30–60 plus cover,        0.6
                              cotton fibre itself ~1500): parts are solid volumes
Leather    860                tanned leather 860–1000                               0.6
Ceramic    2400               porcelain 2300–2500, stoneware ~2200                  0.5
Stone      2700               granite 2600–2800, marble 2550–2750                   0.6
Rubber     1100               natural rubber 930, filled/synthetic 1100–1500        1.0
                              (rubber on dry surfaces: 0.8–1.2)
Other      1000               unknown: water density as a neutral guess             0.5
=========  =================  ==================================================  ==========

Friction is the sliding coefficient MuJoCo's ``friction`` attribute takes first. Colours are
neutral renderings of each family (Glass is translucent) so exports are readable at a glance.

Joint defaults of the simulation MJCF (``jax3dc.export.simulation``), from the family of the part a
joint moves. Each is a multiple of the joint's effective inertia I (kg·m² for a hinge, kg for a
slide: the moved parts' inertia about the axis, or their mass), so a joint behaves alike at any
size: damping = I / τ (τ: seconds for a freely moving part to lose 1/e of its speed), dry friction
(MuJoCo's ``frictionloss``) = I × a (a: the acceleration it resists; for a slide μ·g of a part on
its runners), armature = I × r (r: the hinge or runner hardware's inertia, as a share of the part's).
The servos of the export and of the physics checks are critically damped at 60 rad/s for I plus
armature, so they overcome this friction to within a / 3600 (under 3 mrad, 3 mm).

=========  ======  ==========  =====  ===========================================================
family     τ (s)   a (/s²)     r      why
=========  ======  ==========  =====  ===========================================================
Wood       0.5     3.0         0.03   wooden runners and hinges rub (wood on wood μ ≈ 0.3)
Metal      2.0     0.5         0.005  steel hinges and ball-bearing slides run free; heavy parts
Plastic    1.0     2.0         0.02   moulded hinges and runners (μ ≈ 0.2); light parts
Glass      2.0     0.5         0.01   glass doors hang on metal hinges; dense parts
Fabric     0.25    5.0         0.08   padded parts fold against their cover; hardware outweighs foam
Leather    0.5     4.0         0.03   stitched folds bend stiffly
Ceramic    1.0     1.0         0.01   lids on plastic or metal hinges; dense parts
Stone      1.0     1.0         0.01   as ceramic
Rubber     0.2     5.0         0.02   rubber drags and absorbs (μ ≈ 1)
Other      1.0     2.0         0.02   unknown: plastic-like middle values
=========  ======  ==========  =====  ===========================================================
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class MaterialProps:
    density_kg_m3: float
    friction: float
    rgba: tuple[float, float, float, float]
    joint_decay_s: float  # τ: joint damping = effective inertia / τ
    joint_friction: float  # a: joint frictionloss = effective inertia × a (rad/s² hinge, m/s² slide)
    joint_armature: float  # r: joint armature = effective inertia × r


MATERIALS: dict[str, MaterialProps] = {
    "Wood": MaterialProps(700.0, 0.45, (0.66, 0.47, 0.28, 1.0), 0.5, 3.0, 0.03),
    "Metal": MaterialProps(7850.0, 0.6, (0.72, 0.73, 0.76, 1.0), 2.0, 0.5, 0.005),
    "Plastic": MaterialProps(1050.0, 0.35, (0.88, 0.88, 0.85, 1.0), 1.0, 2.0, 0.02),
    "Glass": MaterialProps(2500.0, 0.9, (0.70, 0.85, 0.92, 0.35), 2.0, 0.5, 0.01),
    "Fabric": MaterialProps(250.0, 0.6, (0.42, 0.48, 0.60, 1.0), 0.25, 5.0, 0.08),
    "Leather": MaterialProps(860.0, 0.6, (0.38, 0.22, 0.13, 1.0), 0.5, 4.0, 0.03),
    "Ceramic": MaterialProps(2400.0, 0.5, (0.95, 0.95, 0.93, 1.0), 1.0, 1.0, 0.01),
    "Stone": MaterialProps(2700.0, 0.6, (0.56, 0.55, 0.52, 1.0), 1.0, 1.0, 0.01),
    "Rubber": MaterialProps(1100.0, 1.0, (0.12, 0.12, 0.12, 1.0), 0.2, 5.0, 0.02),
    "Other": MaterialProps(1000.0, 0.5, (0.60, 0.60, 0.60, 1.0), 1.0, 2.0, 0.02),
}

