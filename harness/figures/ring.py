"""Fig. 12: reflective caustics from a metal ring (cube-map caustic faces)."""

from __future__ import annotations

import matplotlib.pyplot as plt

from harness.figures.common import FigureContext, receiver_scores, shared_white, show
from harness.studies.runner import frame_seconds


def figure_12(ctx: FigureContext):
    """Fig. 12: the ring's reflective caustic, caustics mapping vs reference."""

    scene = ctx.scene("metal_ring")
    ref, method = ctx.reference(scene), ctx.realtime(scene)
    fig, axes = plt.subplots(1, 3, figsize=(9, 3.2))
    white = shared_white(ref.camera)
    show(axes[0], method.camera, white=white, receiver=False, title="caustics mapping")
    show(axes[1], ref.camera, white=white, receiver=False, title="reference")
    rwhite = shared_white(ref.receivers[0].irradiance)
    show(axes[2], method.receivers[0].irradiance, white=rwhite, receiver=True,
         title="caustics mapping receiver map")
    scores = receiver_scores(method.receivers[0].irradiance, ref.receivers[0].irradiance,
                             region=ctx.region(scene))
    data = {"scene": scene.name, "passes": method.metadata.get("passes"),
            "map_faces": method.metadata.get("map_faces"),
            "frame_ms": frame_seconds(method.timings) * 1e3,
            **{f"receiver_{k}": v for k, v in scores.items()}}
    caption = (f"Fig. 12 analogue: metal ring, one specular reflection, point light with "
               f"cube-map faces {', '.join(data['map_faces'] or [])}. Receiver relMSE "
               f"{scores['relmse']:.3g}, SSIM {scores['ssim']:.3f}, flux ratio "
               f"{scores['flux_ratio']:.3f}; {data['frame_ms']:.1f} ms per frame.")
    return ctx.save("fig12", fig, caption=caption, data=data)
