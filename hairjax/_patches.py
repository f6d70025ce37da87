"""Polygonal hair patches drawn with the four-pass scheme (docs/model.md §18,
scheuermann-2004 slides 4–6, 14–17).

Geometry only (NumPy float64) except `composite_patches`, which applies the per-fragment
weights to JAX point colours, so the image stays differentiable in the shading parameters
(the weights depend on geometry and the alpha texture only, as `_render.composite`'s do).

- `patch_mesh`: every strand becomes a ribbon of quads (two triangles per segment) of
  world width w, in the plane spanned by T and B = normalise(N × T) (N the strand normal
  away from the hair centre, §17), wound so that the right-hand-rule normal is +N: the
  front face points outward. Vertices 2p (u = 0) and 2p + 1 (u = 1) sit at p ∓ (w/2)B.
- `patch_alpha`: one strand's across-profile p(t): 1 for |t − ½| ≤ c/2 (the opaque core,
  slide 6's "fully opaque regions"), falling linearly to 0 at the strand's edges.
- `patch_texture`: the alpha texture a(u, v): n strands side by side across the patch,
  each the profile p times its peak alpha, each cut at its own length along v; peak and
  length from an integer hash of (patch, strand), so JAX and GLSL draw the same texture.
- `patch_fragments`: every triangle rasterised at the pixel centres as GL does it:
  coverage on the vertices rounded to 1/2^RASTER_SUBPIXEL_BITS px with GL's tie rule,
  attributes from the unrounded positions (`snapped_fragments`), in draw order.
- `four_pass_weights`: per pixel, what slide 17's four passes leave in the colour buffer
  after the head (the scene's occluder, drawn first: slide 16), as weights on the
  fragments' colours, the head's colour and the background.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._constants import PATCH_OPAQUE_EPS
from ._geometry._occluder import drawable_triangles, occluder_hits
from ._geometry._ordering import hair_centre, static_order
from ._geometry._projection import View, camera_view
from ._geometry._snapped import snapped_fragments
from ._geometry_stage._stage import geometry_stage
from ._patch_texture import patch_alpha, patch_texture, strand_hash
from ._shading import occluder_colors, point_colors
from ._shading._scheuermann_inputs import strand_normals
from ._values._strands import tangents

__all__ = [
    "scene_patches",
    "scene_point_colors",
    "render_patches",
    "Patches",
    "patch_mesh",
    "patch_alpha",
    "patch_texture",
    "strand_hash",
    "snapped_fragments",
    "PatchFragments",
    "patch_fragments",
    "PatchWeights",
    "four_pass_weights",
    "composite_patches",
]


@dataclasses.dataclass(frozen=True)
class Patches:
    """A patch mesh: `vertices` `[V, 3]`, `triangles` `[T, 3]` in draw order, `u` `[V]`
    across-coordinate, `point` `[V]` the strand point whose colour a vertex carries,
    `core` the opaque fraction c of a strand's profile. The texture (§18): `v` `[V]` the
    along-coordinate (0 at the root, 1 at the tip; None: 0 everywhere), `patch` `[V]` the
    patch a vertex belongs to (None: 0), `strands` n across a patch, `strand_alpha` m the
    lowest peak alpha of the semi-transparent ones, `tips` λ the spread of their lengths."""

    vertices: np.ndarray
    triangles: np.ndarray
    u: np.ndarray
    point: np.ndarray
    core: float
    v: np.ndarray | None = None
    patch: np.ndarray | None = None
    strands: int = 1
    strand_alpha: float = 1.0
    tips: float = 0.0

    def alpha(self, u: np.ndarray, v: np.ndarray, patch: np.ndarray) -> np.ndarray:
        """The texture a(u, v) of patch `patch` (`patch_texture` with this mesh's settings)."""
        return patch_texture(u, v, patch, self.core, self.strands, self.strand_alpha, self.tips)

    def along(self) -> np.ndarray:
        """`v` per vertex (0 where the mesh has none)."""
        return np.zeros(len(self.vertices)) if self.v is None else np.asarray(self.v, np.float64)

    def patch_of(self) -> np.ndarray:
        """`patch` per vertex (0 where the mesh has none)."""
        return np.zeros(len(self.vertices), np.int64) if self.patch is None else np.asarray(self.patch)


def patch_mesh(
    points: np.ndarray,
    offsets: np.ndarray,
    tangent: np.ndarray,
    normal: np.ndarray,
    width: float,
    core: float,
    centre: np.ndarray,
    strands: int = 1,
    strand_alpha: float = 1.0,
    tips: float = 0.0,
) -> Patches:
    """Ribbons of world width `width` along the strands (module docstring). Triangles are
    drawn in slide 14's static inside-to-outside order of their segments (`static_order`
    about `centre`), the segment's two triangles one after the other. Strand s is patch s;
    its point j of J gets v = j/(J − 1).

    **Arguments:** `points` `[P, 3]`, `offsets` `[S + 1]`, unit `tangent` and `normal`
    `[P, 3]` (N ⟂ T), `width` > 0, `core` ∈ [0, 1], `centre` `[3]`; the texture's
    `strands` ≥ 1, `strand_alpha` ∈ [0, 1], `tips` ∈ [0, 1] (`patch_texture`)."""
    if not (np.isfinite(width) and width > 0):
        raise ValueError(f"patch width must be a positive finite number, got {width!r}")
    if not (0.0 <= core <= 1.0):
        raise ValueError(f"opaque core must lie in [0, 1], got {core!r}")
    if not (int(strands) == strands and strands >= 1):
        raise ValueError(f"strands across a patch must be an integer ≥ 1, got {strands!r}")
    if not (0.0 <= strand_alpha <= 1.0):
        raise ValueError(f"strand alpha must lie in [0, 1], got {strand_alpha!r}")
    if not (0.0 <= tips <= 1.0):
        raise ValueError(f"strand tips must lie in [0, 1], got {tips!r}")
    points = np.asarray(points, np.float64)
    b = np.cross(normal, tangent)
    norm = np.linalg.norm(b, axis=1, keepdims=True)
    # Fires at points without tangent or normal (repeated points): a zero-width spot there.
    b = np.where(norm > 0, b / np.where(norm > 0, norm, 1.0), 0.0)
    vertices = np.empty((2 * len(points), 3))
    vertices[0::2] = points - 0.5 * width * b
    vertices[1::2] = points + 0.5 * width * b
    u = np.tile([0.0, 1.0], len(points))
    strand_of = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    index = np.arange(len(points)) - np.asarray(offsets)[strand_of]
    # Fires for one-point strands only (no segment, no triangle): v = 0 there.
    along = index / np.maximum(np.diff(offsets)[strand_of] - 1, 1)
    first = np.flatnonzero(strand_of[:-1] == strand_of[1:])  # segments (p, p + 1)
    segments = np.stack([first, first + 1], axis=1)
    p = first[static_order(points, segments, centre)]
    # (L_p, L_p+1, R_p) and (R_p, L_p+1, R_p+1): normal (L_p+1 − L_p) × (R_p − L_p) ∝ T × B = N.
    tris = np.stack(
        [
            np.stack([2 * p, 2 * p + 2, 2 * p + 1], axis=1),
            np.stack([2 * p + 1, 2 * p + 2, 2 * p + 3], axis=1),
        ],
        axis=1,
    ).reshape(-1, 3)
    return Patches(
        vertices,
        tris.astype(np.int64),
        u,
        np.repeat(np.arange(len(points)), 2),
        float(core),
        np.repeat(along, 2),
        np.repeat(strand_of, 2),
        int(strands),
        float(strand_alpha),
        float(tips),
    )


@dataclasses.dataclass(frozen=True)
class PatchFragments:
    """All fragments at pixel centres, sorted by pixel, then draw order: `pixel`, `draw`
    (triangle position in draw order), `depth` D, `front` (faces the viewer), `alpha`
    a(u), `lam` `[F, 3]` perspective-correct barycentrics, `corner_point` `[F, 3]` the
    strand points whose colours they weigh."""

    pixel: np.ndarray
    draw: np.ndarray
    depth: np.ndarray
    front: np.ndarray
    alpha: np.ndarray
    lam: np.ndarray
    corner_point: np.ndarray


def patch_fragments(view: View, patches: Patches) -> PatchFragments:
    """The patches rasterised at `view`'s pixel centres as GL does (`snapped_fragments`:
    coverage on rounded vertices with GL's tie rule, attributes unrounded), of the
    triangles with all three vertices beyond the near plane.

    A triangle faces the viewer when its projection is counter-clockwise in GL's window
    coordinates (y up), i.e. its signed area in pixel coordinates (y down) is negative;
    for a triangle wound with outward normal n that is n·(eye − P) > 0."""
    tri_all = patches.triangles
    drawn = drawable_triangles(view, patches.vertices, tri_all)
    tri = tri_all[drawn]
    xy, depth = view.project(patches.vertices)
    parts = list(snapped_fragments(view, xy, depth, tri))
    k = np.concatenate([p[0] for p in parts]) if parts else np.zeros(0, np.int64)
    pixel = np.concatenate([p[1] for p in parts]) if parts else np.zeros(0, np.int64)
    lam = np.concatenate([p[2] for p in parts]) if parts else np.zeros((0, 3))
    front = np.concatenate([p[3] for p in parts]) if parts else np.zeros(0, bool)
    corners = tri[k]
    point = np.einsum("ni,nij->nj", lam, patches.vertices[corners])
    d = (point - view.origin) @ view.forward
    u = np.sum(lam * patches.u[corners], axis=1)
    v = np.sum(lam * patches.along()[corners], axis=1)
    draw = drawn[k]
    order = np.lexsort((draw, pixel))
    return PatchFragments(
        pixel[order],
        draw[order],
        d[order],
        front[order],
        patches.alpha(u[order], v[order], patches.patch_of()[corners[order, 0]]),
        lam[order],
        patches.point[corners[order]],
    )


@dataclasses.dataclass(frozen=True)
class PatchWeights:
    """The four passes' result as weights: colour = Σ_f `weight`_f c_f + `background`_pixel
    · background + `head`_pixel · the head's colour there, alpha channel `coverage`."""

    fragment: np.ndarray  # [F]
    background: np.ndarray  # [H*W]
    coverage: np.ndarray  # [H*W]
    head: np.ndarray  # [H*W] (0 without a head)


def four_pass_weights(frags: PatchFragments, num_pixels: int, head_depth=None) -> PatchWeights:
    """docs/model.md §18, per pixel, fragments in draw order, after the head (the scene's
    occluder, slide 16: "draw head first") wrote its depth `head_depth` `[H*W]` (∞ where it
    misses; None: no head) and its colour:

    1. Z₁ = min of the head's depth and D over opaque fragments (a ≥ 1 − PATCH_OPAQUE_EPS);
       ∞ if neither.
    2. The colour buffer holds the opaque fragment with D = Z₁ (the last drawn of equal
       ones: Z test EQUAL, no blending), else the head where it covers the pixel (alpha
       1), else the background (alpha 0).
    3. Over it, in draw order, each transparent back-facing fragment with D < Z₁.
    4. Then each transparent front-facing fragment with D < Z, where Z starts at Z₁ and
       becomes D after each fragment drawn (Z writes on).
    "Over": C ← a c + (1 − a) C, A ← a + (1 − a) A.
    """
    f = frags.pixel.size
    opaque = frags.alpha >= 1.0 - PATCH_OPAQUE_EPS
    head = np.full(num_pixels, np.inf) if head_depth is None else np.asarray(head_depth, np.float64)
    z1 = head.copy()
    np.minimum.at(z1, frags.pixel[opaque], frags.depth[opaque])
    # Pass 2: opaque fragments at exactly Z₁; fragments are sorted by draw within a pixel,
    # so the last such fragment of each pixel is the one left in the buffer.
    at_z1 = np.flatnonzero(opaque & (frags.depth == z1[frags.pixel]))
    last = np.r_[frags.pixel[at_z1][1:] != frags.pixel[at_z1][:-1], True] if at_z1.size else at_z1 > 0
    base = np.full(num_pixels, -1, np.int64)
    base[frags.pixel[at_z1[last]]] = at_z1[last]
    # Passes 3 and 4: the accepted transparent fragments.
    back = ~opaque & ~frags.front & (frags.depth < z1[frags.pixel])
    front_cand = np.flatnonzero(~opaque & frags.front)
    front = np.zeros(f, bool)
    z = z1.copy()
    # The r-th front candidate of every pixel at once: its Z test against the running Z.
    rank = _rank(frags.pixel[front_cand])
    for r in range(int(rank.max(initial=-1)) + 1):
        idx = front_cand[rank == r]
        pix = frags.pixel[idx]
        passed = frags.depth[idx] < z[pix]
        front[idx[passed]] = True
        z[pix[passed]] = frags.depth[idx[passed]]
    # Blending order: pass 3's fragments (draw order), then pass 4's. Weight of an accepted
    # fragment: a · Π(1 − a) of those blended after it in its pixel; the base's: Π over all.
    seq = np.concatenate([np.flatnonzero(back), np.flatnonzero(front)])
    seq = seq[np.argsort(frags.pixel[seq], kind="stable")]
    a = frags.alpha[seq]
    pix = frags.pixel[seq]
    weight = np.zeros(f)
    trans = np.ones(num_pixels)  # Π(1 − a) of the fragments blended after, back to front
    # Suffix products per pixel: walk from the last blended fragment of each pixel back.
    from_end = _rank(pix[::-1])[::-1]
    for r in range(int(from_end.max(initial=-1)) + 1):
        sel = from_end == r
        weight[seq[sel]] = a[sel] * trans[pix[sel]]
        trans[pix[sel]] *= 1.0 - a[sel]
    has_base = base >= 0
    weight[base[has_base]] = trans[has_base]
    # The head stays where no opaque fragment met Z₁ (then Z₁ is the head's depth).
    on_head = ~has_base & np.isfinite(head)
    background = np.where(has_base | on_head, 0.0, trans)
    coverage = np.where(has_base | on_head, 1.0, 1.0 - trans)
    return PatchWeights(weight, background, coverage, np.where(on_head, trans, 0.0))


def _rank(pixel: np.ndarray) -> np.ndarray:
    """Position of each entry within its run of equal `pixel` values (`pixel` grouped)."""
    n = pixel.size
    if n == 0:
        return np.zeros(0, np.int64)
    start = np.r_[True, pixel[1:] != pixel[:-1]]
    return np.arange(n) - np.maximum.accumulate(np.where(start, np.arange(n), 0))


def composite_patches(
    frags: PatchFragments,
    weights: PatchWeights,
    colors: Float[Array, "P 3"],
    background: Float[Array, " 3"],
    height: int,
    width: int,
    head_colors: Float[Array, "HW 3"] | None = None,
) -> Float[Array, "H W 4"]:
    """The image: Σ_f w_f Σ_i λ'_i c(point_i) + w_bg · background + w_head · the head's
    colour per pixel (`head_colors`, where `weights.head` is non-zero), alpha channel the
    coverage. Linear in the JAX `colors` and `head_colors` (so differentiable in the
    shading parameters)."""
    lam = jnp.asarray(frags.lam)
    frag_color = jnp.einsum("fi,fic->fc", lam, colors[jnp.asarray(frags.corner_point)])
    rgb = jax.ops.segment_sum(
        jnp.asarray(weights.fragment)[:, None] * frag_color,
        jnp.asarray(frags.pixel),
        num_segments=height * width,
    )
    rgb = rgb + jnp.asarray(weights.background)[:, None] * jnp.asarray(background)[None, :]
    if head_colors is not None:
        rgb = rgb + jnp.asarray(weights.head)[:, None] * head_colors
    image = jnp.concatenate([rgb, jnp.asarray(weights.coverage)[:, None]], axis=1)
    return image.reshape(height, width, 4)


def scene_patches(scene) -> Patches:
    """The scene's strands as patches (`scene.patches`: width and texture): N away from
    `hair_centre` (§17's strand normal), drawn in the static order about it (slide 14)."""
    points, offsets = scene.strands.points, scene.strands.offsets
    tangent = tangents(points, offsets)
    centre = hair_centre(points, offsets)
    normal = strand_normals(points, tangent, centre)
    g = scene.patches
    return patch_mesh(
        points, offsets, tangent, normal, g.width, g.opaque_core, centre, g.strands, g.strand_alpha, g.tips
    )


def scene_point_colors(scene, params=None) -> Float[Array, "P 3"]:
    """The strands' shaded point colours (`point_colors`: the scene's shading model, with
    the strands' own self-shadows, §7), which the patches interpolate."""
    return point_colors(geometry_stage(scene), scene.params if params is None else params)


def render_patches(scene, params=None) -> Float[Array, "H W 4"]:
    """`scene` (with `scene.patches`) drawn as hair patches: slide 17's four passes as
    per-pixel weights (NumPy) on the JAX point colours, so differentiable in `params`. The
    scene's occluder, if any, is the head drawn first (slide 16): its depth per pixel
    centre (§9, §13) primes the Z test and its colour (§13, lit and shadowed as in the
    strand renderer) is the backdrop of the pixels it covers."""
    params = scene.params if params is None else params
    view = camera_view(scene.camera)
    hw = view.width * view.height
    frags = patch_fragments(view, scene_patches(scene))
    geometry = geometry_stage(scene)
    head_depth = head_colors = None
    if scene.occluder is not None:
        head_depth, _, _ = occluder_hits(view, scene.occluder)
        # The geometry stage's occluder pixels are exactly those where head_depth is finite.
        head_colors = (
            jnp.zeros((hw, 3), jnp.result_type(float))
            .at[jnp.asarray(geometry.occluder_pixel)]
            .set(occluder_colors(geometry, params))
        )
    weights = four_pass_weights(frags, hw, head_depth)
    return composite_patches(
        frags,
        weights,
        point_colors(geometry, params),
        jnp.asarray(scene.background),
        view.height,
        view.width,
        head_colors,
    )
