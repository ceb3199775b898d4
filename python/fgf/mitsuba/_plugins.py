"""The ``fgf`` / ``nonexponential`` medium plugins and the ``fgf_volpath``
integrator, built for the Mitsuba variant that is current when
:func:`make_plugins` runs (``docs/theory.md`` §4).

Mitsuba's medium interface only samples exponential free flights and its
``sample_interaction`` cannot be overridden from Python, so the medium
plugins here only carry their parameters; ``fgf_volpath`` does the free-flight
sampling itself, with the semantics of fgf's renderer
(``crates/fgf-render/src/integrator/`` and ``medium/``):

* a path is cut into segments; a segment starts "on a surface" at the camera,
  at a light and at **every** surface crossing (null boundaries included),
  and "in the medium" after a scattering event;
* free flights are drawn from ``p = T_sm`` (energy-conserving kernel, any
  start; reciprocal kernel from a surface) or ``T_mm`` (reciprocal kernel
  from a medium vertex); a segment is passed with probability ``Tr`` or
  ``T_ms`` respectively;
* shadow rays multiply, per segment, ``Tr`` (energy-conserving, and
  reciprocal ``T_ss`` from a surface) or ``T_ms`` (reciprocal from a medium
  vertex); every crossing restarts the segment on a surface;
* RGB media use path-level hero-channel spectral MIS: one channel, picked per
  camera sample, draws every flight; each channel's path pdf relative to the
  hero's is tracked in ``r_u`` and a contribution is weighted by
  ``1/mean(r_u)`` (the balance heuristic over the channels' whole paths);
* next-event estimation at scattering events and smooth surfaces, combined
  with phase/BSDF sampling by the power heuristic; Russian roulette once the
  depth exceeds ``rr_depth`` with survival ``min(max(thr)·η²/mean(r_u), 0.95)``;
  ``max_depth`` counts medium scattering events and non-null surface
  interactions, as Mitsuba's ``volpath`` does.

Mitsuba's own ``homogeneous`` media are handled as the exponential model
(``k = 0``); other media (``heterogeneous``) are refused with an error.
"""

from __future__ import annotations

import importlib
import math
from typing import Any, Callable, Optional, TypeVar

import numpy as np

from . import _drmath as dm
from ._params import (
    KERNELS,
    FlightTable,
    MediumData,
    MediumParameterError,
    MediumSpec,
    build_models,
    exponential_data,
    medium_data,
    parse_spec,
)

# Dr.Jit and Mitsuba as `Any`: their classes depend on the variant chosen at
# run time (``mi.Float`` is a Python float in scalar_rgb, an LLVM array in
# llvm_ad_rgb), which no static type describes.
dr: Any = importlib.import_module("drjit")
mi: Any = importlib.import_module("mitsuba")

_F = TypeVar("_F", bound=Callable[..., Any])
#: ``dr.syntax``, typed: it rewrites a function's ``if``/``while`` on Dr.Jit
#: masks into symbolic branches and loops, keeping its signature.
syntax: Callable[[_F], _F] = dr.syntax

#: Largest ``max_depth`` (``-1`` in the XML means unbounded, as in Mitsuba).
UNBOUNDED = 2**32 - 1


def _not(m: Any) -> Any:
    """Logical not of a mask in every variant (``~`` is wrong on Python bools)."""
    return dr.select(m, False, True)


def _pick(c: Any, hero: Any) -> Any:
    """Channel ``hero`` of a colour, lane by lane."""
    return dr.select(hero == 0, c[0], dr.select(hero == 1, c[1], c[2]))


def _mis(a: Any, b: Any) -> Any:
    """Power heuristic ``a²/(a²+b²)``."""
    a2 = a * a
    s = a2 + b * b
    return dr.select(s > 0, a2 * dr.rcp(dr.select(s > 0, s, 1.0)), 0.0)


class _Params:
    """One lane's medium parameters, gathered from the scene tables."""

    __slots__ = ("sigma", "k", "e", "sbar", "albedo", "recip", "hero")

    def __init__(self, sigma: Any, k: Any, e: Any, sbar: Any, albedo: Any, recip: Any, hero: Any) -> None:
        self.sigma, self.k, self.e, self.sbar = sigma, k, e, sbar
        self.albedo, self.recip, self.hero = albedo, recip, hero


class SceneTables:
    """The media of one scene as flat arrays indexed by a *slot* (0 = no
    medium), in Dr.Jit arrays for the JIT variants and Python lists for the
    scalar ones; plus the map from Mitsuba's medium pointers to slots."""

    def __init__(self, data: list[MediumData], ptr_slots: dict[int, int], jit: bool) -> None:
        self.jit = jit
        n = len(data) + 1
        f = {name: np.zeros(3 * n, np.float64) for name in ("sigma", "k", "e", "sbar", "albedo")}
        recip = np.zeros(n, np.uint32)
        # Per slot, channel and flight (surface, medium): table offset and size.
        off = np.zeros((2, 3 * n), np.uint32)
        size = np.full((2, 3 * n), 2.0)
        s_all: list[np.ndarray] = [np.zeros(2)]
        d_all: list[np.ndarray] = [np.zeros(2)]
        pos = 2
        seen: dict[int, int] = {}
        for i, md in enumerate(data, start=1):
            recip[i] = 1 if md.reciprocal else 0
            for c in range(3):
                g = md.gamma[c]
                j = 3 * i + c
                f["sigma"][j], f["k"][j], f["e"][j], f["sbar"][j] = g.sigma, g.k, g.e, g.sigma_bar
                f["albedo"][j] = md.albedo[c]
                for fl in range(2):
                    tab: Optional[FlightTable] = md.tables[c][fl] if md.tables else None
                    if tab is None:
                        continue
                    if id(tab) not in seen:
                        seen[id(tab)] = pos
                        s_all.append(tab.s)
                        d_all.append(tab.hd)
                        pos += tab.n
                    off[fl, j] = seen[id(tab)]
                    size[fl, j] = tab.n
        self.n_slots = n
        self.ptr_slots = ptr_slots
        s = np.concatenate(s_all)
        d = np.concatenate(d_all)
        if jit:
            F, U = mi.Float, mi.UInt32
            self.f = {k: F(v.astype(np.float32)) for k, v in f.items()}
            self.recip = U(recip)
            self.off = [U(off[0]), U(off[1])]
            self.size = [F(size[0].astype(np.float32)), F(size[1].astype(np.float32))]
            self.s, self.d = F(s.astype(np.float32)), F(d.astype(np.float32))
            ids = max(ptr_slots) + 1 if ptr_slots else 1
            id2slot = np.zeros(ids, np.uint32)
            for pid, sl in ptr_slots.items():
                id2slot[pid] = sl
            self.id2slot = U(id2slot)
        else:
            self.f = {k: [float(x) for x in v] for k, v in f.items()}
            self.recip = [bool(x) for x in recip]
            self.off = [[int(x) for x in off[0]], [int(x) for x in off[1]]]
            self.size = [[float(x) for x in size[0]], [float(x) for x in size[1]]]
            self.s, self.d = [float(x) for x in s], [float(x) for x in d]

    # -- lookups ----------------------------------------------------------
    def slot_of(self, medium: Any) -> Any:
        """The slot of a medium pointer (0 for none)."""
        if self.jit:
            ids = dr.reinterpret_array(mi.UInt32, medium)
            return dr.gather(mi.UInt32, self.id2slot, ids, ids < dr.width(self.id2slot))
        if medium is None:
            return 0
        return self.ptr_slots[medium.ptr]

    def _g(self, arr: Any, idx: Any, mask: Any = True, kind: Any = None) -> Any:
        if self.jit:
            return dr.gather(kind or mi.Float, arr, idx, mask)
        return arr[idx] if mask else 0

    def params(self, slot: Any, hero: Any, active: Any) -> _Params:
        j = slot * 3

        def col(name: str) -> Any:
            a = self.f[name]
            return mi.Color3f(self._g(a, j, active), self._g(a, j + 1, active), self._g(a, j + 2, active))

        recip = self._g(self.recip, slot, active, mi.UInt32) != 0
        return _Params(col("sigma"), col("k"), col("e"), col("sbar"), col("albedo"), recip, hero)

    def sample_flight(self, p: _Params, slot: Any, u: Any, from_medium: Any, active: Any) -> Any:
        """A flight distance of channel ``p.hero`` from the variate ``u``:
        inverse cdf of ``1 - T_ms`` when ``from_medium`` (reciprocal kernel
        after a scattering event), else of ``1 - Tr``."""
        sig, k, e, sbar = (_pick(v, p.hero) for v in (p.sigma, p.k, p.e, p.sbar))
        y = -dm.ln_1p(-u)
        # e = 0 (white noise, exponential): exponential with σ̄.
        t_exp = y * dr.rcp(sbar)
        # e = 1 (Davis, k-fBm): (1 + k t)^(-α) with α = σ/k, and the medium
        # flight's (1 + k t)^(-α-1).
        k_safe = dr.select(k > 0, k, 1.0)
        a = dr.select(from_medium, y * dr.rcp(sig * dr.rcp(k_safe) + 1.0), y * k_safe * dr.rcp(sig))
        t_davis = dm.expm1(a) * dr.rcp(k_safe)
        # 0 < e < 1 (pink noise, Davis–Weinstein): the tabulated inverse.
        closed = (e == 0) | (k == 0) | (e == 1)
        tab = active & _not(closed) & (y > 0)
        j = slot * 3 + p.hero
        off0 = self._g(self.off[0], j, tab, mi.UInt32)
        off1 = self._g(self.off[1], j, tab, mi.UInt32)
        n0 = self._g(self.size[0], j, tab)
        n1 = self._g(self.size[1], j, tab)
        off = dr.select(from_medium, off1, off0)
        n = dr.select(from_medium, n1, n0)
        ln_y = dr.log(dr.select(y > 0, y, 1.0))
        xc, ext, f = dm.table_position(ln_y, dr.select(tab, n, 2.0))
        i = off + mi.UInt32(xc - f)
        s0 = self._g(self.s, i, tab)
        d0 = self._g(self.d, i, tab)
        s1 = self._g(self.s, i + 1, tab)
        d1 = self._g(self.d, i + 1, tab)
        ln_t = dm.hermite(s0, d0, s1, d1, f) + ext * dr.select(ext < 0, d0, d1)
        t_tab = dr.exp(ln_t)
        t = dr.select((e == 0) | (k == 0), t_exp, dr.select(e == 1, t_davis, t_tab))
        return dr.select(y > 0, t, 0.0)


def _medium_props(plugin: str, props: Any) -> dict[str, Any]:
    """The plain parameters of a medium's ``Properties`` (nested objects
    such as the phase function are taken by Mitsuba's base class)."""
    out: dict[str, Any] = {}
    T = mi.Properties.Type
    for name in props.keys():
        if props.was_queried(name):
            continue
        ty = props.type(name)
        if ty == T.Object:
            obj = props[name]
            if isinstance(obj, mi.PhaseFunction):
                continue
            raise MediumParameterError(
                f"{plugin} medium: nested {type(obj).__name__} '{name}' is not supported by fgf.mitsuba "
                "(only a phase function; a 'density' grid needs fgf's own renderer)"
            )
        v = props[name]
        if ty == T.Color:
            v = (float(v[0]), float(v[1]), float(v[2]))
        elif ty in (T.Float, T.Integer):
            v = float(v)
        out[name] = v
    return out


def make_plugins() -> tuple[Callable[[Any], Any], Callable[[Any], Any], Callable[[Any], Any]]:
    """Classes of the current variant: constructors of the ``fgf`` and
    ``nonexponential`` media and of the ``fgf_volpath`` integrator.

    (``mitsuba`` resolves ``mi.Float`` etc. to the current variant at each
    access; the functions decorated with ``dr.syntax`` are recompiled by
    Dr.Jit and must not use closure variables, only globals and ``self``.)"""
    jit = bool(dr.is_jit_v(mi.Float))

    class FgfMedium(mi.Medium):  # type: ignore[misc]
        """A non-exponential medium (parameters only; see the module docs)."""

        def __init__(self, props: Any, plugin: str) -> None:
            mi.Medium.__init__(self, props)
            self.spec: MediumSpec = parse_spec(plugin, _medium_props(plugin, props))
            sig = self.spec.sigma_t
            self.m_is_homogeneous = True
            self.m_has_spectral_extinction = not (sig[0] == sig[1] == sig[2])

        # Mitsuba's own integrators (volpath) see the exponential medium of
        # the same mean extinction: only fgf_volpath uses the model.
        def get_majorant(self, mei: Any, active: Any = True) -> Any:
            return mi.UnpolarizedSpectrum(mi.Color3f(*self.spec.sigma_t))

        def get_scattering_coefficients(self, mei: Any, active: Any = True) -> Any:
            sigma_t = mi.UnpolarizedSpectrum(mi.Color3f(*self.spec.sigma_t))
            sigma_s = sigma_t * mi.UnpolarizedSpectrum(mi.Color3f(*self.spec.albedo))
            return sigma_s, mi.UnpolarizedSpectrum(0.0), sigma_t

        def intersect_aabb(self, ray: Any) -> Any:
            return mi.Bool(True), mi.Float(0.0), mi.Float(dr.inf)

        def to_string(self) -> str:
            return f"FgfMedium[{self.spec}]"

    class FgfVolpath(mi.SamplingIntegrator):  # type: ignore[misc]
        """The ``fgf_volpath`` integrator (see the module docs)."""

        def __init__(self, props: Any) -> None:
            mi.SamplingIntegrator.__init__(self, props)
            md = int(props.get("max_depth", -1))
            if md < -1:
                raise ValueError(f"fgf_volpath: invalid max_depth = {md} (valid: -1 for unbounded, or >= 0)")
            self.max_depth = UNBOUNDED if md == -1 else md
            rr = int(props.get("rr_depth", 5))
            if rr < 0:
                raise ValueError(f"fgf_volpath: invalid rr_depth = {rr} (valid: >= 0)")
            self.rr_depth = rr
            kernel = props.get("kernel", "")
            if kernel not in ("",) + KERNELS:
                raise ValueError(f"fgf_volpath: invalid kernel = '{kernel}' (valid: {', '.join(KERNELS)})")
            self.kernel: Optional[str] = kernel or None
            self.hide = bool(props.get("hide_emitters", False))
            self._cache: Optional[tuple[Any, SceneTables]] = None
            self.jit = jit

        def aov_names(self) -> list[str]:
            return []

        def to_string(self) -> str:
            return f"FgfVolpath[max_depth={self.max_depth}, rr_depth={self.rr_depth}, kernel={self.kernel}]"

        # -- scene set-up (once per scene) -------------------------------
        def prepare(self, scene: Any) -> SceneTables:
            """Collect the scene's media into :class:`SceneTables`."""
            key = scene.ptr
            if self._cache is not None and self._cache[0] == key:
                return self._cache[1]
            media: dict[int, Any] = {}
            interior_of: dict[int, list[Any]] = {}
            for shape in scene.shapes():
                for m, inner in ((shape.interior_medium(), True), (shape.exterior_medium(), False)):
                    if m is None:
                        continue
                    media.setdefault(m.ptr, m)
                    if inner:
                        interior_of.setdefault(m.ptr, []).append(shape)
            for sensor in scene.sensors():
                m = sensor.get_medium()
                if m is not None:
                    media.setdefault(m.ptr, m)
            data: list[MediumData] = []
            ptr_slots: dict[int, int] = {}
            for ptr, m in media.items():
                data.append(self._medium_data(m, interior_of.get(ptr, [])))
                pid = int(dr.reinterpret_array(mi.UInt32, mi.MediumPtr(m))[0]) if jit else ptr
                ptr_slots[pid] = len(data)
            tables = SceneTables(data, ptr_slots, jit)
            self._cache = (key, tables)
            return tables

        def _medium_data(self, m: Any, shapes: list[Any]) -> MediumData:
            if isinstance(m, FgfMedium):
                spec = m.spec
                length = None
                if spec.needs_length:
                    if not shapes:
                        raise MediumParameterError(
                            f"{spec.plugin} medium: a k-fBm medium that is no shape's interior needs 'length'"
                        )
                    bb = mi.ScalarBoundingBox3f()
                    for s in shapes:
                        b = s.bbox()
                        bb.expand(mi.ScalarPoint3f(*(float(b.min[i]) for i in range(3))))
                        bb.expand(mi.ScalarPoint3f(*(float(b.max[i]) for i in range(3))))
                    ext = [float(bb.max[i] - bb.min[i]) for i in range(3)]
                    length = math.sqrt(sum(x * x for x in ext))
                kernel = self.kernel or spec.kernel
                return medium_data(build_models(spec, length), spec.albedo, kernel == "reciprocal")
            params = mi.traverse(m)
            keys = set(params.keys())
            if not (m.is_homogeneous() and {"sigma_t.value.value", "albedo.value.value"} <= keys):
                raise MediumParameterError(
                    f"fgf_volpath: medium {m.class_name()} is not supported "
                    "(valid: fgf, nonexponential, or homogeneous with constant sigma_t and albedo)"
                )

            def rgb(v: Any) -> list[float]:
                a = np.array(v, dtype=np.float64).reshape(-1)
                return [float(a[0])] * 3 if a.size == 1 else [float(x) for x in a[:3]]

            scale = float(np.array(params["scale"]).reshape(-1)[0]) if "scale" in keys else 1.0
            sigma = [s * scale for s in rgb(params["sigma_t.value.value"])]
            return exponential_data(sigma, rgb(params["albedo.value.value"]))

        # -- path tracing -------------------------------------------------
        def _mei(self, ray: Any, t: Any, medium: Any) -> Any:
            mei = dr.zeros(mi.MediumInteraction3f)
            mei.t = t
            mei.time = ray.time
            mei.wavelengths = ray.wavelengths
            mei.p = ray(t)
            mei.wi = -ray.d
            mei.sh_frame = mi.Frame3f(mei.wi)
            mei.medium = medium
            return mei

        def _interaction(self, p: Any, n: Any, time: Any, wavelengths: Any) -> Any:
            it = dr.zeros(mi.Interaction3f)
            it.p = p
            it.n = n
            it.t = 0.0
            it.time = time
            it.wavelengths = wavelengths
            return it

        @syntax
        def _shadow(self, scene: Any, st: SceneTables, ray: Any, target: Any, slot: Any,
                    from_medium: Any, active: Any) -> Any:
            """Transmittance of a shadow ray to the point ``target`` through
            null boundaries and media, per RGB channel (deterministic)."""
            trn = mi.Spectrum(1.0)
            slot = mi.UInt32(slot)
            fm = mi.Bool(from_medium)
            active = mi.Bool(active)
            while active:
                si = scene.ray_intersect(ray, active)
                hit = si.is_valid()
                seg = dr.select(hit, si.t, ray.maxt)
                if slot != 0:
                    p = st.params(slot, 0, active)
                    trs = dr.select(fm & p.recip, dm.medium_surface(p.sigma, p.k, p.e, seg),
                                    dm.tr(p.sigma, p.k, p.e, seg))
                    trn *= trs
                null = mi.Bool(False)
                if hit:
                    null = mi.has_flag(si.bsdf(ray).flags(), mi.BSDFFlags.Null)
                    if null & si.is_medium_transition():
                        slot = st.slot_of(si.target_medium(ray.d))
                    ray = si.spawn_ray_to(target)
                    fm = mi.Bool(False)
                trn = dr.select(hit & _not(null), 0.0, trn)
                active &= hit & null & dr.any(trn != 0.0)
            return trn

        @syntax
        def sample(self, scene: Any, sampler: Any, ray_: Any, medium: Any = None,
                   active_: Any = True) -> Any:
            st = self.prepare(scene)
            ray = mi.Ray3f(ray_)
            # max_depth = 0: nothing, not even emitters seen directly.
            active = mi.Bool(active_) & (self.max_depth > 0)
            L = mi.Spectrum(0.0)
            thr = mi.Spectrum(1.0)
            r_u = mi.Spectrum(1.0)
            inv_mis = mi.Float(1.0)
            depth = mi.UInt32(0)
            eta = mi.Float(1.0)
            if self.jit:
                med = dr.zeros(mi.MediumPtr) if medium is None else mi.MediumPtr(medium)
            else:
                med = medium
            slot = mi.UInt32(st.slot_of(med))
            from_medium = mi.Bool(False)
            specular = mi.Bool(True)
            prev_it = dr.zeros(mi.Interaction3f)
            prev_pdf = mi.Float(1.0)
            hero = mi.UInt32(dr.minimum(3.0 * sampler.next_1d(active), 2.0))
            bctx = mi.BSDFContext()
            max_depth = self.max_depth
            rr_depth = self.rr_depth
            hide = self.hide

            while active:
                si = scene.ray_intersect(ray, active)
                t_surf = si.t
                scattered = mi.Bool(False)
                t_fl = mi.Float(dr.inf)
                if active & (slot != 0):
                    p = st.params(slot, hero, active)
                    fm = from_medium & p.recip
                    t_fl = st.sample_flight(p, slot, sampler.next_1d(active), fm, active)
                    scattered = t_fl < t_surf
                    t_ev = dr.select(scattered, t_fl, t_surf)
                    kf = dr.select(fm, dm.medium_medium(p.sigma, p.k, p.e, p.sbar, t_ev),
                                   dm.surface_medium(p.sigma, p.k, p.e, t_ev))
                    sf = dr.select(fm, dm.medium_surface(p.sigma, p.k, p.e, t_ev),
                                   dm.tr(p.sigma, p.k, p.e, t_ev))
                    v = dr.select(scattered, kf, sf)
                    vh = _pick(v, hero)
                    ok = (vh > 0) & dr.isfinite(vh)
                    ratio = dr.select(ok, v * dr.rcp(dr.select(ok, vh, 1.0)), 1.0)
                    thr *= dr.select(scattered, p.albedo * ratio, dr.select(ok, ratio, 0.0))
                    r_u *= ratio
                    # Only ratios matter: rescale both against under/overflow.
                    rm = dr.max(r_u)
                    resc = (rm > 0) & ((rm < 1e-4) | (rm > 1e4))
                    sc = dr.select(resc, dr.rcp(dr.select(resc, rm, 1.0)), 1.0)
                    r_u *= sc
                    thr *= sc
                    inv_mis = dr.rcp(dr.mean(r_u))

                interacted = mi.Bool(False)
                if scattered:
                    depth += 1
                active &= _not(scattered) | (depth < max_depth)
                # --- a scattering event in the medium -------------------
                if active & scattered:
                    mei = self._mei(ray, t_fl, med)
                    phase = med.phase_function()
                    pctx = mi.PhaseFunctionContext(sampler)
                    ds, em_w = scene.sample_emitter_direction(mei, sampler.next_2d(active), False, active)
                    sray = mei.spawn_ray_to(ds.p)
                    trn = self._shadow(scene, st, sray, ds.p, slot, True, active & (ds.pdf > 0))
                    f_val, f_pdf = phase.eval_pdf(pctx, mei, ds.d, active)
                    w_l = dr.select(ds.delta, 1.0, _mis(ds.pdf, f_pdf))
                    L += thr * em_w * trn * f_val * (w_l * inv_mis)
                    wo, p_w, p_pdf = phase.sample(pctx, mei, sampler.next_1d(active),
                                                  sampler.next_2d(active), active)
                    thr *= p_w
                    prev_it = self._interaction(mei.p, mi.Normal3f(0.0), ray.time, ray.wavelengths)
                    prev_pdf = p_pdf
                    specular = mi.Bool(False)
                    ray = mei.spawn_ray(wo)
                    from_medium = mi.Bool(True)
                    active &= p_pdf > 0
                    interacted = mi.Bool(True)
                # --- a surface, or the environment ----------------------
                if active & _not(scattered):
                    emitter = si.emitter(scene)
                    if (emitter != None) & _not((depth == 0) & hide):  # noqa: E711
                        ds_e = mi.DirectionSample3f(scene, si, prev_it)
                        em_pdf = scene.pdf_emitter_direction(prev_it, ds_e, _not(specular))
                        w_e = dr.select(specular, 1.0, _mis(prev_pdf, em_pdf))
                        L += thr * emitter.eval(si) * (w_e * inv_mis)
                    valid = si.is_valid()
                    active &= valid
                    if valid:
                        bsdf = si.bsdf(ray)
                        null = mi.has_flag(bsdf.flags(), mi.BSDFFlags.Null)
                        if null:
                            # An index-matched boundary: straight on, new segment.
                            if si.is_medium_transition():
                                med = si.target_medium(ray.d)
                                slot = st.slot_of(med)
                            ray = si.spawn_ray(ray.d)
                            from_medium = mi.Bool(False)
                        interact = _not(null) & (depth + 1 < max_depth)
                        active &= null | interact
                        if interact:
                            smooth = mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
                            if smooth:
                                ds, em_w = scene.sample_emitter_direction(si, sampler.next_2d(smooth), False, smooth)
                                wi_l = si.to_local(ds.d)
                                b_val, b_pdf = bsdf.eval_pdf(bctx, si, wi_l, smooth)
                                lit = smooth & (ds.pdf > 0) & dr.any(b_val != 0.0)
                                s_med = dr.select(si.is_medium_transition(), si.target_medium(ds.d), med)
                                sray = si.spawn_ray_to(ds.p)
                                trn = self._shadow(scene, st, sray, ds.p, st.slot_of(s_med), False, lit)
                                w_l = dr.select(ds.delta, 1.0, _mis(ds.pdf, b_pdf))
                                L += dr.select(lit, thr * em_w * trn * b_val * (w_l * inv_mis), 0.0)
                            bs, b_w = bsdf.sample(bctx, si, sampler.next_1d(interact),
                                                  sampler.next_2d(interact), interact)
                            thr *= b_w
                            eta *= bs.eta
                            depth += 1
                            specular = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
                            prev_pdf = bs.pdf
                            prev_it = self._interaction(si.p, si.n, ray.time, ray.wavelengths)
                            wo = si.to_world(bs.wo)
                            if si.is_medium_transition():
                                med = si.target_medium(wo)
                                slot = st.slot_of(med)
                            ray = si.spawn_ray(wo)
                            from_medium = mi.Bool(False)
                            active &= bs.pdf > 0
                            interacted = mi.Bool(True)
                active &= dr.any(thr != 0.0)
                # --- Russian roulette (the path weight thr/mean(r_u)) ---
                if active & interacted & (depth > rr_depth):
                    q = dr.minimum(dr.max(thr) * inv_mis * eta * eta, 0.95)
                    survive = sampler.next_1d(active) < q
                    thr *= dr.rcp(dr.select(q > 0, q, 1.0))
                    active &= survive
            return L, mi.Bool(True), []

    def medium_fgf(props: Any) -> Any:
        return FgfMedium(props, "fgf")

    def medium_nonexp(props: Any) -> Any:
        return FgfMedium(props, "nonexponential")

    def integrator(props: Any) -> Any:
        return FgfVolpath(props)

    return medium_fgf, medium_nonexp, integrator
