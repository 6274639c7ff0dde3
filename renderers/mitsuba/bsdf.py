"""``chain_dielectric``: a smooth dielectric whose branches follow the scene's effects.

Mitsuba's own ``dielectric`` always chooses reflection or transmission by Fresnel.
The caustics-mapping method (and the photon tracer's chain filter) assume every
photon takes the transmitted branch with weight one unless the scene asks for
Fresnel. This BSDF lets the ptracer camera obey the same rule:

* ``fresnel = true``: reflect with probability F (Fresnel, exact dielectric
  formula), transmit otherwise; weight one (the choice is the estimator).
* ``fresnel = false``: always transmit with weight one. Under total internal
  reflection there is no transmitted branch: with ``tir_reflects = false`` (the
  event-chain mode) the particle is **absorbed** -- exactly as the photon tracer
  drops a photon whose chain TIR breaks; with ``tir_reflects = true`` (all
  L S+ D paths) it reflects with weight one.
* Beer-Lambert absorption: a particle leaving the medium (incident from the
  inside, ``cos_theta_i < 0``) has just travelled ``si.t`` metres inside it, so its
  weight is multiplied by exp(-sigma * si.t) per channel. This covers closed
  objects; the segment from an open water surface to the floor ends on a diffuse
  receiver and is not attenuated in the camera image (the photon tracer does it).

Radiance transport scales transmission by eta_ti^2 (solid-angle compression), as
Mitsuba's ``dielectric`` does; importance transport (ptracer) does not.
"""

from __future__ import annotations

__all__ = ["BSDF_NAME", "register"]

BSDF_NAME = "chain_dielectric"


def register(mi, dr) -> None:
    """Register the plugin with Mitsuba (idempotent)."""

    class ChainDielectric(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.eta = float(props["eta"]) if "eta" in props else 1.5
            self.fresnel = bool(props["fresnel"]) if "fresnel" in props else False
            self.tir_reflects = bool(props["tir_reflects"]) if "tir_reflects" in props else False
            sigma = [float(props[f"sigma_{c}"]) if f"sigma_{c}" in props else 0.0
                     for c in "rgb"]
            self.sigma = mi.Color3f(*sigma)
            self.absorbing = any(s > 0 for s in sigma)
            flags = (mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.FrontSide
                     | mi.BSDFFlags.BackSide)
            tflags = (mi.BSDFFlags.DeltaTransmission | mi.BSDFFlags.FrontSide
                      | mi.BSDFFlags.BackSide | mi.BSDFFlags.NonSymmetric)
            self.m_components = [flags, tflags]
            self.m_flags = flags | tflags

        def sample(self, ctx, si, sample1, sample2, active):
            cos_i = mi.Frame3f.cos_theta(si.wi)
            # F, cos of the transmitted angle (signed), eta_it, eta_ti.
            f, cos_t, eta_it, eta_ti = mi.fresnel(cos_i, self.eta)
            tir = f >= 1.0
            if self.fresnel:
                reflect = sample1 <= f
                weight = mi.Color3f(1.0)
            else:
                reflect = tir & self.tir_reflects
                weight = dr.select(tir & ~self.tir_reflects, mi.Color3f(0.0), mi.Color3f(1.0))
            bs = mi.BSDFSample3f()
            bs.wo = dr.select(reflect, mi.reflect(si.wi), mi.refract(si.wi, cos_t, eta_ti))
            bs.eta = dr.select(reflect, 1.0, eta_it)
            bs.pdf = 1.0
            bs.sampled_component = dr.select(reflect, mi.UInt32(0), mi.UInt32(1))
            bs.sampled_type = dr.select(
                reflect,
                mi.UInt32(+mi.BSDFFlags.DeltaReflection),
                mi.UInt32(+mi.BSDFFlags.DeltaTransmission),
            )
            if ctx.mode == mi.TransportMode.Radiance:
                factor = dr.select(reflect, 1.0, eta_ti)
                weight *= factor * factor
            if self.absorbing:
                inside = cos_i < 0
                weight *= dr.select(inside, dr.exp(-self.sigma * si.t), 1.0)
            return bs, dr.select(active, weight, mi.Color3f(0.0))

        def eval(self, ctx, si, wo, active):
            return mi.Color3f(0.0)

        def pdf(self, ctx, si, wo, active):
            return mi.Float(0.0)

        def eval_pdf(self, ctx, si, wo, active):
            return mi.Color3f(0.0), mi.Float(0.0)

        def to_string(self):
            return f"ChainDielectric[eta={self.eta}, fresnel={self.fresnel}]"

    mi.register_bsdf(BSDF_NAME, ChainDielectric)
