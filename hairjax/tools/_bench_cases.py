"""What `hairjax bench` measures: the configurations (fur balls × image sizes), their scene,
the targets the table marks, and the names of the stages (BENCHMARKS.md)."""

from __future__ import annotations

__all__ = [
    "configurations",
    "config_name",
    "bench_scene",
    "TARGETS",
    "STAGES",
    "STAGE_LABELS",
    "GL_PASSES",
    "JAX_TARGET_CONFIGS",
    "JAX_TARGET_RATIO",
    "PEAK_RSS_TARGET_GIB",
    "BACKENDS",
    "QUICK_REPEATS",
]

# Scene of the benchmark: the default scene's camera and light (hairjax/scenes/default.toml).
EYE = (0.0, 0.3, 4.2)
TARGET = (0.0, -0.1, 0.0)
FOV = 40.0
POINTS = 16
ORDERING_BINS = 256

# kim-2003 §6: 0.7 M segments/s for the depth-bin ordering on a 700 MHz Pentium III.
KIM_2003_SEGMENTS_PER_S = 0.7e6

TARGETS = {
    "full_render_s": 2.0,  # 100k strands at 1024² (only that configuration)
    "shading_s": 0.100,  # every configuration
    "gradient_over_shading": 3.0,  # every configuration
    "ordering_msegments_per_s": 20.0,  # every configuration
}
FULL_RENDER_TARGET_CONFIG = (100_000, 1024)
# --backend both: the GL full render of FULL_RENDER_TARGET_CONFIG (64 maps) is no slower
# than the JAX path's, i.e. JAX full render / GL full render >= 1.
GL_TARGET_RATIO = 1.0
# --backend both, the geometry stage on the device: the JAX full render no slower than the
# GL renderer on the same machine, i.e. JAX / GL <= 1, at these (strands, size).
JAX_TARGET_CONFIGS = ((20_000, 512), (100_000, 1024))
JAX_TARGET_RATIO = 1.0
# Peak resident memory of a configuration's process, at FULL_RENDER_TARGET_CONFIG.
PEAK_RSS_TARGET_GIB = 3.0
BACKENDS = ("jax", "gl", "both")
# Sub-timings of `render_gl`, in the order of its passes (GLResult.timings keys).
GL_PASSES = ("upload", "shadows", "camera pass")

# Stage keys of the JSON ("stages"), in table order; set-up sub-steps follow as
# "geometry_setup/<step>" with the step names of `Setup.timings`.
STAGES = ("geometry_setup", "geometry_opacity", "shading", "gradient", "full_render")
STAGE_LABELS = {
    "geometry_setup": "geometry set-up",
    "geometry_opacity": "geometry opacity (JAX)",
    "shading": "shading stage",
    "gradient": "gradient wrt kd, ks, p, kappa",
    "full_render": "full render",
}

QUICK_REPEATS = 2


def configurations(quick: bool) -> list[dict]:
    """The benchmark configurations: fur balls × image sizes (`--quick`: one tiny one)."""
    if quick:
        return [dict(strands=2_000, size=128, maps=8, map_resolution=64)]
    return [
        dict(strands=n, size=s, maps=64, map_resolution=256) for n in (20_000, 100_000) for s in (512, 1024)
    ]


def config_name(cfg: dict) -> str:
    n = cfg["strands"]
    count = f"{n // 1000}k" if n % 1000 == 0 else str(n)
    return f"{count} @ {cfg['size']}x{cfg['size']}"


def bench_scene(cfg: dict):
    from .._geometry._ordering import Ordering
    from .._geometry._shadows import Shadows
    from .._scene._procedural import furball
    from .._scene._scene import Scene
    from .._shading import KajiyaKay, ShadingParams
    from .._values._camera import Camera
    from .._values._light import Light

    hair = furball(strands=cfg["strands"], points=POINTS)
    return Scene(
        strands=hair,
        camera=Camera(eye=EYE, target=TARGET, fov=FOV, width=cfg["size"], height=cfg["size"]),
        light=Light(kind="directional", direction=(-0.6, -0.8, -0.5)),
        shading=KajiyaKay(
            ShadingParams(kd=(0.55, 0.35, 0.2), ks=0.35, shininess=30.0, kappa=1.0, ambient=0.05)
        ),
        shadows=Shadows(method="opacity-maps", maps=cfg["maps"], resolution=cfg["map_resolution"]),
        ordering=Ordering(method="bins", bins=ORDERING_BINS),
        background=(0.02, 0.02, 0.03),
        name="bench",
    )
