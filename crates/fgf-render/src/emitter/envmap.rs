//! `envmap`: environment radiance from a latitude–longitude image, with
//! Mitsuba 3's parameterisation and filtering, importance-sampled by
//! luminance.
//!
//! * Direction ↔ image: in the emitter's local frame (`to_world⁻¹`), a
//!   direction `d` has `u = atan2(d.x, -d.z)/2π` (wrapped to [0, 1)) and
//!   `v = acos(d.y)/π`: `+y` is the top row, `-z` the image's left edge.
//! * Radiance: the image is a grid of `(W + 1) × H` vertices (a copy of
//!   the first column closes it periodically), vertex `(x, y)` at
//!   `u = (x + ½)/W`, `v = y/(H - 1)`; between vertices it is bilinear.
//! * Sampling: piecewise constant over the grid's `W × (H - 1)` cells, each
//!   weighted by the mean luminance of its corners times `sin θ` at its
//!   centre (positive wherever the radiance is); a cell is chosen from the
//!   marginal over rows and the conditional over columns, each by an alias
//!   table (`docs/theory.md` §7.20), then a point uniformly in it. The
//!   solid-angle pdf is `p_uv / (2π² sin θ)`.
//! * `Envmap::sample8` draws eight samples at once with the 8-lane
//!   vectors of `crate::lanes` (gathers from the same tables), each with
//!   the bits of [`Envmap::sample`]: the paths that go on in step
//!   (`World::li_beam`) draw their light samples so.

use crate::lanes::{F8, I8, M8};
use crate::math::{self, bin_index, mul_normalize8};
use crate::spectrum::Spectrum;
use fgf_scene::RgbImage;
use glam::{Mat3, Mat4, Vec3A};
use std::f32::consts::PI;

#[derive(Debug, Clone)]
pub struct Envmap {
    /// Image width `W` and height `H`.
    w: usize,
    h: usize,
    /// `(W + 1) × H` vertex radiances, row-major, as RGB and a zero (the
    /// layout of a [`Spectrum`], which the lanes read as one table of `f32`).
    data: Vec<[f32; 4]>,
    to_world: Mat3,
    to_local: Mat3,
    /// Per cell, the pdf with respect to the unit square of `(u, v)`.
    cell_pdf: Vec<f32>,
    /// The alias table of the rows (`H - 1` bins), and those of the
    /// columns of each row, one row after another (`W` bins each).
    row_alias: Vec<AliasBin>,
    col_alias: Vec<AliasBin>,
}

/// One bin of an alias table (Walker's method, built by Vose's): the bits
/// of the probability of keeping the bin's own index, and the index given
/// otherwise (one table of `u32` for the lanes' gathers). Choosing an
/// index costs one read, where inverting a cumulative table walks it: on
/// a mesh lit by an environment map those walks, their dependent reads and
/// their mispredicted loop exits were 3–4 % of the render
/// (`docs/benchmarks.md`).
type AliasBin = [u32; 2];

/// The alias table of `weights` (non-negative, not all zero): bin `k`
/// keeps `k` with probability `prob[k]` and gives `alias[k]` otherwise, so
/// that index `k` is chosen with probability `weights[k] / Σ weights`
/// when the bin is chosen uniformly (`docs/theory.md` §7.20).
fn alias_table(weights: &[f64]) -> Vec<AliasBin> {
    let n = weights.len();
    let total: f64 = weights.iter().sum();
    // Each weight scaled so that the mean is 1.
    let mut scaled: Vec<f64> = weights.iter().map(|w| w * n as f64 / total).collect();
    let mut table: Vec<AliasBin> = (0..n).map(|k| [1f32.to_bits(), k as u32]).collect();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&k| scaled[k] < 1.0);
    while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
        small.pop();
        table[s] = [(scaled[s] as f32).to_bits(), l as u32];
        // The large bin gives the small one what it lacks.
        scaled[l] -= 1.0 - scaled[s];
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // What is left keeps its own index (1 up to rounding).
    table
}

/// The index that the alias table `table` (`n` bins, lane `l` reading its
/// bins from `table[2·base[l]..]`) gives for `u` in `[0, 1)`, and `u`'s
/// position within that index's share, in `[0, 1)`: `u` chooses a bin,
/// and what is left of it chooses between the bin's two indices and then
/// the position. [`alias_pick`] is the scalar function, with the same bits.
#[inline(always)]
fn alias_pick8(table: &[u32], n: i32, base: I8, u: F8) -> (I8, F8) {
    let x = u.mul(F8::splat(n as f32));
    let k = bin_index8(x, n);
    // (`x` may round up to `k + 1` in the last bin.)
    let f = x.sub(k.to_f32()).min(F8::splat(ONE_BELOW));
    let e = base.add(k).mul(I8::splat(2));
    let p = I8::gather(table, e).to_bits_f32();
    let alias = I8::gather(table, e.add(I8::splat(1)));
    let own = f.lt(p);
    let r = own.select(f.div(p), f.sub(p).div(F8::splat(1.0).sub(p)));
    let r = r.max(F8::splat(0.0)).min(F8::splat(WITHIN_TOP));
    (own.select_i8(k, alias), r)
}

/// [`alias_pick8`] of one variate, on the bins `table`.
#[inline(always)]
fn alias_pick(table: &[AliasBin], u: f32) -> (usize, f32) {
    let n = table.len();
    let x = u * n as f32;
    let k = bin_index(x, n);
    let f = (x - k as f32).min(ONE_BELOW);
    let [p, alias] = table[k];
    let p = f32::from_bits(p);
    let (k, r) = if f < p {
        (k, f / p)
    } else {
        (alias as usize, (f - p) / (1.0 - p))
    };
    (k, r.clamp(0.0, WITHIN_TOP))
}

/// The largest `f32` below 1.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;
/// The largest position within a cell that a sample takes: off its far
/// edge, which is the next cell's.
const WITHIN_TOP: f32 = 0.999_999;

/// A vertex radiance of the table.
#[inline(always)]
fn texel(t: [f32; 4]) -> Spectrum {
    Spectrum::from_vec4(glam::Vec4::from_array(t))
}

/// Luminance of linear Rec. 709 RGB.
#[inline]
fn luminance(c: Spectrum) -> f32 {
    0.212_671 * c.x + 0.715_160 * c.y + 0.072_169 * c.z
}

impl Envmap {
    pub fn new(img: &RgbImage, to_world: Mat4) -> Envmap {
        let (w, h) = (img.width, img.height);
        let mut data = Vec::with_capacity((w + 1) * h);
        for y in 0..h {
            for x in 0..=w {
                let i = (y * w + x % w) * 3;
                data.push([img.data[i], img.data[i + 1], img.data[i + 2], 0.0]);
            }
        }
        let (nx, ny) = (w, h - 1);
        let mut weight = vec![0f64; nx * ny];
        for j in 0..ny {
            let sin_t = ((j as f64 + 0.5) / ny as f64 * std::f64::consts::PI).sin();
            for i in 0..nx {
                let v = |x: usize, y: usize| luminance(texel(data[y * (w + 1) + x])) as f64;
                let l = 0.25 * (v(i, j) + v(i + 1, j) + v(i, j + 1) + v(i + 1, j + 1));
                weight[j * nx + i] = l * sin_t;
            }
        }
        let total: f64 = weight.iter().sum();
        // An all-black map: sample uniformly (its radiance is zero anyway).
        if !(total > 0.0) {
            weight.iter_mut().for_each(|x| *x = 1.0);
        }
        let total: f64 = weight.iter().sum();
        let rows: Vec<f64> = weight.chunks_exact(nx).map(|r| r.iter().sum()).collect();
        let row_alias = alias_table(&rows);
        // A row of zero weight is never chosen; its columns are uniform.
        let uniform = vec![1.0; nx];
        let col_alias: Vec<AliasBin> = weight
            .chunks_exact(nx)
            .zip(&rows)
            .flat_map(|(r, &sum)| alias_table(if sum > 0.0 { r } else { &uniform }))
            .collect();
        let cells = (nx * ny) as f64;
        let cell_pdf: Vec<f32> = weight.iter().map(|x| (x / total * cells) as f32).collect();
        let l = Mat3::from_mat4(to_world);
        // Escaped rays and light samples read them anywhere.
        crate::huge::advise(&data);
        crate::huge::advise(&cell_pdf);
        crate::huge::advise(&col_alias);
        Envmap {
            w,
            h,
            data,
            to_world: l,
            to_local: l.inverse(),
            cell_pdf,
            row_alias,
            col_alias,
        }
    }

    /// Grid coordinates `(u - ½/W wrapped, v)` and `sin θ` of a world direction.
    #[inline]
    fn grid_uv(&self, d: Vec3A) -> (f32, f32, f32) {
        let l = (self.to_local * d).normalize();
        let u = math::atan2(l.x, -l.z) * (0.5 / PI) - 0.5 / self.w as f32;
        let v = math::acos(l.y.clamp(-1.0, 1.0)) * (1.0 / PI);
        let sin_t = (l.x * l.x + l.z * l.z).sqrt();
        (u - u.floor(), v, sin_t)
    }

    /// Radiance arriving from world direction `d` (toward the environment).
    #[inline]
    pub fn eval(&self, d: Vec3A) -> Spectrum {
        let (u, v, _) = self.grid_uv(d);
        self.lookup(u, v)
    }

    fn lookup(&self, u: f32, v: f32) -> Spectrum {
        let (x, y) = (u * self.w as f32, v * (self.h - 1) as f32);
        let (ix, iy) = (bin_index(x, self.w), bin_index(y, self.h - 1));
        let (fx, fy) = (x - ix as f32, y - iy as f32);
        let row = self.w + 1;
        let at = |x: usize, y: usize| texel(self.data[y * row + x]);
        let a = at(ix, iy) * (1.0 - fx) + at(ix + 1, iy) * fx;
        let b = at(ix, iy + 1) * (1.0 - fx) + at(ix + 1, iy + 1) * fx;
        a * (1.0 - fy) + b * fy
    }

    #[inline]
    fn cell(&self, u: f32, v: f32) -> usize {
        let (nx, ny) = (self.w, self.h - 1);
        let i = bin_index(u * nx as f32, nx);
        let j = bin_index(v * ny as f32, ny);
        j * nx + i
    }

    /// Solid-angle pdf of [`Self::sample`] producing world direction `d`.
    #[inline]
    pub fn pdf(&self, d: Vec3A) -> f32 {
        let (u, v, sin_t) = self.grid_uv(d);
        self.pdf_at(u, v, sin_t)
    }

    #[inline]
    fn pdf_at(&self, u: f32, v: f32, sin_t: f32) -> f32 {
        if sin_t <= 0.0 {
            return 0.0;
        }
        self.cell_pdf[self.cell(u, v)] / (2.0 * PI * PI * sin_t)
    }

    /// [`Self::eval`] and [`Self::pdf`] of one direction, which they share
    /// the costly mapping to the image of.
    #[inline]
    pub fn eval_pdf(&self, d: Vec3A) -> (Spectrum, f32) {
        let (u, v, sin_t) = self.grid_uv(d);
        (self.lookup(u, v), self.pdf_at(u, v, sin_t))
    }

    /// A world direction toward the environment, its radiance and pdf.
    pub fn sample(&self, u: [f32; 2]) -> Option<(Vec3A, Spectrum, f32)> {
        let (nx, ny) = (self.w, self.h - 1);
        let (j, fv) = alias_pick(&self.row_alias, u[1]);
        let (i, fu) = alias_pick(&self.col_alias[j * nx..(j + 1) * nx], u[0]);
        let gu = (i as f32 + fu) / nx as f32;
        let gv = (j as f32 + fv) / ny as f32;
        // θ = π·gv and φ = 2π·(gu + ½/W), as turns.
        let (st, ct) = math::sin_cos_2pi(0.5 * gv);
        if st <= 0.0 {
            return None;
        }
        let (sp, cp) = math::sin_cos_2pi(gu + 0.5 / self.w as f32);
        let local = Vec3A::new(sp * st, ct, -cp * st);
        let d = (self.to_world * local).normalize();
        let pdf = self.cell_pdf[j * nx + i] / (2.0 * PI * PI * st);
        if !(pdf > 0.0) {
            return None;
        }
        Some((d, self.lookup(gu, gv), pdf))
    }
}

/// Light samples of eight lanes (see [`Envmap::sample8`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct EnvSample8 {
    /// World directions, radiances (x, y, z and R, G, B) and pdfs.
    pub d: [F8; 3],
    pub value: [F8; 3],
    pub pdf: F8,
    /// The lanes with a sample (where the scalar `sample` returns `Some`).
    pub ok: M8,
}

impl Envmap {
    /// [`Self::sample`] of eight lanes, lane `l` at `[u0[l], u1[l]]` (both
    /// in `[0, 1)`), with the scalar function's bits in each lane.
    #[inline(always)]
    pub(crate) fn sample8(&self, u0: F8, u1: F8) -> EnvSample8 {
        let (nx, ny) = (self.w as i32, self.h as i32 - 1);
        let (j, fv) = alias_pick8(self.row_alias.as_flattened(), ny, I8::splat(0), u1);
        let (i, fu) = alias_pick8(self.col_alias.as_flattened(), nx, j.mul(I8::splat(nx)), u0);
        let gu = i.to_f32().add(fu).div(F8::splat(nx as f32));
        let gv = j.to_f32().add(fv).div(F8::splat(ny as f32));
        // θ = π·gv and φ = 2π·(gu + ½/W), as turns.
        let (st, ct) = math::sin_cos_2pi8(F8::splat(0.5).mul(gv));
        let (sp, cp) = math::sin_cos_2pi8(gu.add(F8::splat(0.5 / self.w as f32)));
        let local = [sp.mul(st), ct, F8::splat(0.0).sub(cp).mul(st)];
        let d = mul_normalize8(self.to_world, local);
        let cell = F8::gather(&self.cell_pdf, j.mul(I8::splat(nx)).add(i));
        let pdf = cell.div(F8::splat(2.0 * PI * PI).mul(st));
        let zero = F8::splat(0.0);
        EnvSample8 {
            d,
            value: self.lookup8(gu, gv),
            pdf,
            ok: zero.lt(st).and(zero.lt(pdf)),
        }
    }

    /// [`Self::eval_pdf`] of eight world directions `d` (x, y, z), with
    /// the scalar function's bits in each lane.
    #[inline(always)]
    pub(crate) fn eval_pdf8(&self, d: [F8; 3]) -> ([F8; 3], F8) {
        let (u, v, sin_t) = self.grid_uv8(d);
        let (nx, ny) = (self.w as i32, self.h as i32 - 1);
        let i = bin_index8(u.mul(F8::splat(nx as f32)), nx);
        let j = bin_index8(v.mul(F8::splat(ny as f32)), ny);
        let cell = F8::gather(&self.cell_pdf, j.mul(I8::splat(nx)).add(i));
        let pdf = cell.div(F8::splat(2.0 * PI * PI).mul(sin_t));
        let zero = F8::splat(0.0);
        (self.lookup8(u, v), sin_t.le(zero).select(zero, pdf))
    }

    /// [`Self::grid_uv`] of eight lanes.
    #[inline(always)]
    fn grid_uv8(&self, d: [F8; 3]) -> (F8, F8, F8) {
        let l = mul_normalize8(self.to_local, d);
        let u = math::atan2_8(l[0], l[2].neg())
            .mul(F8::splat(0.5 / PI))
            .sub(F8::splat(0.5 / self.w as f32));
        let y = F8::splat(1.0).min(F8::splat(-1.0).max(l[1]));
        let v = math::acos8(y).mul(F8::splat(1.0 / PI));
        let sin_t = l[0].mul(l[0]).add(l[2].mul(l[2])).sqrt();
        (u.sub(u.floor()), v, sin_t)
    }

    /// [`Self::lookup`] of eight lanes.
    #[inline(always)]
    fn lookup8(&self, u: F8, v: F8) -> [F8; 3] {
        let (x, y) = (
            u.mul(F8::splat(self.w as f32)),
            v.mul(F8::splat((self.h - 1) as f32)),
        );
        let (ix, iy) = (
            bin_index8(x, self.w as i32),
            bin_index8(y, self.h as i32 - 1),
        );
        let (fx, fy) = (x.sub(ix.to_f32()), y.sub(iy.to_f32()));
        let one = F8::splat(1.0);
        let (gx, gy) = (one.sub(fx), one.sub(fy));
        let table = self.data.as_flattened();
        let base = iy
            .mul(I8::splat(self.w as i32 + 1))
            .add(ix)
            .mul(I8::splat(4));
        let next_row = I8::splat(4 * (self.w as i32 + 1));
        std::array::from_fn(|c| {
            let at = |o: I8| F8::gather(table, base.add(o).add(I8::splat(c as i32)));
            let a = at(I8::splat(0)).mul(gx).add(at(I8::splat(4)).mul(fx));
            let b = at(next_row)
                .mul(gx)
                .add(at(next_row.add(I8::splat(4))).mul(fx));
            a.mul(gy).add(b.mul(fy))
        })
    }
}

/// [`bin_index`] of eight lanes, for `x < 2³¹` (NaN and negative lanes give 0).
#[inline(always)]
fn bin_index8(x: F8, n: i32) -> I8 {
    x.trunc().max(I8::splat(0)).min(I8::splat(n - 1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{sample_uniform_sphere, UNIFORM_SPHERE_PDF};
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    fn map() -> Envmap {
        let (w, h) = (16, 9);
        let mut data = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let b = if (x / 4 + y / 3) % 2 == 0 { 4.0 } else { 0.25 };
                data.extend([b * (1.0 + x as f32 / w as f32), b, 0.5 * b]);
            }
        }
        let rot = Mat4::from_rotation_y(0.7) * Mat4::from_rotation_x(0.3);
        Envmap::new(
            &RgbImage {
                width: w,
                height: h,
                data,
            },
            rot,
        )
    }

    /// An alias table gives each index its weight's share: exactly, up to
    /// the rounding of the kept probabilities to `f32`, on weights with
    /// zeros, a dominant one (a sun) and one bin; and choosing by
    /// variates spread over `[0, 1)` hits each index in proportion, with
    /// every position within its share in `[0, 1)`.
    #[test]
    fn alias_tables_give_each_index_its_weight() {
        let weights: [&[f64]; 5] = [
            &[1.0; 7],
            &[0.0, 0.0, 3.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0],
            &[
                1e-6, 1e-6, 1e-6, 1.0, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6,
            ],
            &[5.0, 0.0],
            &[2.5],
        ];
        for w in weights {
            let (n, total) = (w.len(), w.iter().sum::<f64>());
            let table = alias_table(w);
            let mut share = vec![0f64; n];
            for (k, &[p, alias]) in table.iter().enumerate() {
                let p = f32::from_bits(p) as f64;
                assert!((0.0..=1.0).contains(&p), "{w:?}: bin {k} keeps {p}");
                share[k] += p / n as f64;
                share[alias as usize] += (1.0 - p) / n as f64;
            }
            for k in 0..n {
                assert!((share[k] - w[k] / total).abs() < 1e-6, "{w:?}: {share:?}");
            }
            // Variates on a fine grid: the fraction giving each index.
            let m = 1 << 16;
            let mut hits = vec![0usize; n];
            for i in 0..m {
                let (k, r) = alias_pick(&table, (i as f32 + 0.5) / m as f32);
                assert!((0.0..1.0).contains(&r), "{w:?}: position {r}");
                hits[k] += 1;
            }
            for k in 0..n {
                let f = hits[k] as f64 / m as f64;
                assert!((f - w[k] / total).abs() < 1e-3, "{w:?}: {hits:?}");
            }
        }
    }

    /// The sampled directions have the density `pdf`, and `pdf` integrates
    /// to 1 over the sphere; sampled radiance is `eval`.
    #[test]
    fn sampling_matches_pdf_and_eval() {
        let e = map();
        let mut rng = Pcg64::seed_from_u64(5);
        let n = 200_000;
        // E_sample[g/pdf] = ∫ g for g = eval (luminance-like) and g = 1.
        let (mut i1, mut i2, mut i1_2) = (0f64, 0f64, 0f64);
        // Directions on a cell boundary may be placed in the neighbour cell
        // by the round trip through the direction: allow a few per mille.
        let mut off = 0usize;
        for _ in 0..n {
            let (d, l, pdf) = e.sample([rng.random(), rng.random()]).unwrap();
            // (Near the poles the azimuth of the round trip is ill-conditioned.)
            if (e.pdf(d) - pdf).abs() > 2e-3 * pdf
                || (e.eval(d) - l).abs().max_element() > 1e-3 * l.max_element().max(1e-3)
            {
                off += 1;
            }
            let x = (1.0 / pdf) as f64;
            i1 += x;
            i1_2 += x * x;
            i2 += (l.y / pdf) as f64;
        }
        assert!(
            off < n / 500,
            "{off} of {n} samples whose pdf or radiance differ from the direction's"
        );
        let m = i1 / n as f64;
        let se = ((i1_2 / n as f64 - m * m) / n as f64).sqrt();
        assert!(
            (m - 4.0 * std::f64::consts::PI).abs() < 4.0 * se + 1e-3,
            "∫1 = {m} ± {se}"
        );
        // The same integral of the green radiance by uniform sphere sampling.
        let mut u2 = 0f64;
        let mut u2_2 = 0f64;
        for _ in 0..n {
            let d = sample_uniform_sphere([rng.random(), rng.random()]);
            let x = (e.eval(d).y / UNIFORM_SPHERE_PDF) as f64;
            u2 += x;
            u2_2 += x * x;
        }
        let mu = u2 / n as f64;
        let se_u = ((u2_2 / n as f64 - mu * mu) / n as f64).sqrt();
        let mi = i2 / n as f64;
        assert!(
            (mi - mu).abs() < 4.0 * se_u,
            "importance {mi} vs uniform {mu} ± {se_u}"
        );
    }
    /// [`Envmap::eval_pdf8`] gives each lane the scalar function's bits, on
    /// random directions, the poles, the seam and zero components.
    #[test]
    fn eval_pdf8_is_eval_pdf() {
        let e = map();
        let mut rng = Pcg64::seed_from_u64(23);
        let special = [
            Vec3A::Y,
            -Vec3A::Y,
            Vec3A::Z,
            -Vec3A::Z,
            Vec3A::X,
            Vec3A::new(0.0, 0.6, -0.8),
            Vec3A::new(-0.0, -0.6, -0.8),
            e.to_world * Vec3A::new(1e-8, 1.0, 0.0),
        ];
        for round in 0..20_000 {
            let d: [Vec3A; 8] = if round == 0 {
                special
            } else {
                std::array::from_fn(|_| sample_uniform_sphere([rng.random(), rng.random()]))
            };
            let lanes = [0, 1, 2].map(|c| F8::from_array(d.map(|v| v[c])));
            let (v, pdf) = e.eval_pdf8(lanes);
            let (v, pdf) = (v.map(F8::to_array), pdf.to_array());
            for l in 0..8 {
                let (sv, sp) = e.eval_pdf(d[l]);
                let wv = Vec3A::new(v[0][l], v[1][l], v[2][l]);
                let bits = |x: Vec3A| x.to_array().map(f32::to_bits);
                assert_eq!(bits(wv), bits(sv), "{:?}", d[l]);
                assert_eq!(pdf[l].to_bits(), sp.to_bits(), "{:?}", d[l]);
            }
        }
    }

    /// The eight lanes give each lane the scalar sample's bits, on random
    /// variates and at the ends of their range.
    #[test]
    fn sample8_is_sample() {
        let e = map();
        let mut rng = Pcg64::seed_from_u64(17);
        for round in 0..20_000 {
            let mut u0: [f32; 8] = std::array::from_fn(|_| rng.random());
            let mut u1: [f32; 8] = std::array::from_fn(|_| rng.random());
            if round % 5 == 0 {
                (u0[0], u1[1], u0[2], u1[2]) = (0.0, 0.0, 1.0f32.next_down(), 1.0f32.next_down());
            }
            let w = e.sample8(F8::from_array(u0), F8::from_array(u1));
            let ok = w.ok.bitmask();
            let (d, v) = (w.d.map(F8::to_array), w.value.map(F8::to_array));
            let pdf = w.pdf.to_array();
            for l in 0..8 {
                let s = e.sample([u0[l], u1[l]]);
                assert_eq!(ok >> l & 1 == 1, s.is_some(), "lane {l}");
                if let Some((sd, sv, sp)) = s {
                    let bits = |x: Vec3A| x.to_array().map(f32::to_bits);
                    let lane = |a: [[f32; 8]; 3]| Vec3A::new(a[0][l], a[1][l], a[2][l]);
                    assert_eq!(bits(lane(d)), bits(sd), "u = ({}, {})", u0[l], u1[l]);
                    assert_eq!(bits(lane(v)), bits(sv), "u = ({}, {})", u0[l], u1[l]);
                    assert_eq!(pdf[l].to_bits(), sp.to_bits());
                }
            }
        }
    }
}
