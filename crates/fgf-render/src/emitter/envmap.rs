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
//!   marginal over rows and the conditional over columns, then a point
//!   uniformly in it. The solid-angle pdf is `p_uv / (2π² sin θ)`.
//! * [`Envmap::sample8`] draws eight samples at once with the 8-lane
//!   vectors of `crate::lanes` (gathers from the same tables), each with
//!   the bits of [`Envmap::sample`]: the paths that go on in step
//!   (`World::li_beam`) draw their light samples so.

use crate::lanes::{F8, I8, M8};
use crate::math::{self, bin_index};
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
    /// Cumulative row weights (`H` entries, the first 0), normalised to 1 at the end.
    row_cdf: Vec<f32>,
    /// Per row, the cumulative column weights (`W + 1` entries each), normalised.
    col_cdf: Vec<f32>,
    /// Per cell, the pdf with respect to the unit square of `(u, v)`.
    cell_pdf: Vec<f32>,
    /// Guide tables of `row_cdf` and of each row of `col_cdf` (see [`Guide`]).
    row_guide: Guide,
    /// The guide tables of the rows of `col_cdf`, one after another
    /// (`W` bins each).
    col_start: Vec<GuideBin>,
}

/// A guide table of a cumulative table (`n + 1` entries, the first 0, the
/// last 1): for each of `n` equal bins of `u`, the interval [`pick`] returns
/// at the bin's lower end. Inverting at `u` then starts there and walks the
/// few intervals to the answer, instead of a binary search whose dependent
/// loads dominate the cost of sampling the map; the answer is the same.
/// Each bin also keeps the two table values around its start, so that
/// the common case (the answer is that interval) reads one entry rather
/// than the entry and then, dependent on it, the table: on a mesh scene
/// lit by an environment map these two cache misses per row were most of
/// the cost of sampling the map.
#[derive(Debug, Clone)]
struct Guide {
    start: Vec<GuideBin>,
}

/// One bin of a [`Guide`]: the interval `k` and the bits of `cdf[k]` and
/// `cdf[k + 1]` (so that the lanes read the table as one table of `u32`).
type GuideBin = [u32; 3];

impl Guide {
    fn new(cdf: &[f32]) -> Guide {
        let n = cdf.len() - 1;
        let start = (0..n)
            .map(|g| {
                let k = pick_interval(cdf, g as f32 / n as f32);
                [k as u32, cdf[k].to_bits(), cdf[k + 1].to_bits()]
            })
            .collect();
        Guide { start }
    }

    /// [`pick`] on `cdf`, the table this guide was made from.
    #[inline(always)]
    fn pick(&self, cdf: &[f32], u: f32) -> (usize, f32) {
        guide_pick(&self.start, cdf, u)
    }
}

/// [`Guide::pick`] with the guide's table `start` (`cdf.len() - 1` bins).
#[inline(always)]
fn guide_pick(start: &[GuideBin], cdf: &[f32], u: f32) -> (usize, f32) {
    {
        let n = cdf.len() - 1;
        let g = bin_index(u * n as f32, n);
        // The bin's start is exact for `u` at its lower end; rounding of
        // `u · n` may put `u` just below it, hence the walk down as well.
        let [k0, lo, hi] = start[g];
        let (lo, hi) = (f32::from_bits(lo), f32::from_bits(hi));
        let mut k = k0 as usize;
        if k + 1 < n && hi <= u {
            // Up: every step keeps cdf[k] <= u, so no walk down follows.
            k += 1;
            while k + 1 < n && cdf[k + 1] <= u {
                k += 1;
            }
        } else if k > 0 && lo > u {
            k -= 1;
            while k > 0 && cdf[k] > u {
                k -= 1;
            }
        } else {
            return (k, within_interval(lo, hi, u));
        }
        (k, within(cdf, k, u))
    }
}

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
        let mut row_cdf = vec![0f32; ny + 1];
        let mut col_cdf = vec![0f32; ny * (nx + 1)];
        let mut acc = 0f64;
        for j in 0..ny {
            let row: f64 = weight[j * nx..(j + 1) * nx].iter().sum();
            let mut c = 0f64;
            for i in 0..nx {
                c += weight[j * nx + i];
                col_cdf[j * (nx + 1) + i + 1] = if row > 0.0 {
                    (c / row) as f32
                } else {
                    (i + 1) as f32 / nx as f32
                };
            }
            col_cdf[j * (nx + 1) + nx] = 1.0;
            acc += row;
            row_cdf[j + 1] = (acc / total) as f32;
        }
        row_cdf[ny] = 1.0;
        let cells = (nx * ny) as f64;
        let cell_pdf = weight.iter().map(|x| (x / total * cells) as f32).collect();
        let l = Mat3::from_mat4(to_world);
        let row_guide = Guide::new(&row_cdf);
        let col_start = col_cdf
            .chunks_exact(nx + 1)
            .flat_map(|row| Guide::new(row).start)
            .collect();
        Envmap {
            w,
            h,
            data,
            to_world: l,
            to_local: l.inverse(),
            row_cdf,
            col_cdf,
            cell_pdf,
            row_guide,
            col_start,
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
        let (j, fv) = self.row_guide.pick(&self.row_cdf, u[1]);
        let (i, fu) = guide_pick(
            &self.col_start[j * nx..(j + 1) * nx],
            &self.col_cdf[j * (nx + 1)..(j + 1) * (nx + 1)],
            u[0],
        );
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
        let row_guide = self.row_guide.start.as_flattened();
        let (j, fv) = guide_pick8(row_guide, &self.row_cdf, ny, I8::splat(0), I8::splat(0), u1);
        let col_guide = self.col_start.as_flattened();
        let (i, fu) = guide_pick8(
            col_guide,
            &self.col_cdf,
            nx,
            j.mul(I8::splat(nx)),
            j.mul(I8::splat(nx + 1)),
            u0,
        );
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

/// `(m · v).normalize()` of eight vectors `v` (x, y, z), as glam computes
/// it for a `Vec3A`: the columns of `m` scaled and summed in order, then
/// divided by the square root of `(x² + y²) + z²`.
#[inline(always)]
fn mul_normalize8(m: Mat3, v: [F8; 3]) -> [F8; 3] {
    let m = m.to_cols_array_2d();
    let w: [F8; 3] = std::array::from_fn(|r| {
        let c = |k: usize| F8::splat(m[k][r]).mul(v[k]);
        c(0).add(c(1)).add(c(2))
    });
    let len = w[0]
        .mul(w[0])
        .add(w[1].mul(w[1]))
        .add(w[2].mul(w[2]))
        .sqrt();
    w.map(|x| x.div(len))
}

/// [`bin_index`] of eight lanes, for `x < 2³¹` (NaN and negative lanes give 0).
#[inline(always)]
fn bin_index8(x: F8, n: i32) -> I8 {
    x.trunc().max(I8::splat(0)).min(I8::splat(n - 1))
}

/// [`guide_pick`] of eight lanes, each with the scalar function's answer:
/// lane `l` inverts the table of `n + 1` entries at `cdf[first[l]..]` with
/// its guide's bins at `guide[3·base[l]..]` (one row of the envmap's
/// conditional tables, or the marginal with `base = first = 0`).
#[inline(always)]
fn guide_pick8(guide: &[u32], cdf: &[f32], n: i32, base: I8, first: I8, u: F8) -> (I8, F8) {
    let g = bin_index8(u.mul(F8::splat(n as f32)), n);
    let e = base.add(g).mul(I8::splat(3));
    let one = I8::splat(1);
    let mut k = I8::gather(guide, e);
    let mut lo = I8::gather(guide, e.add(one)).to_bits_f32();
    let mut hi = I8::gather(guide, e.add(I8::splat(2))).to_bits_f32();
    let (zero, last) = (I8::splat(0), I8::splat(n - 1));
    let up = last.gt(k).and(hi.le(u));
    let down = k.gt(zero).and(u.lt(lo));
    let walk = up.or(down);
    if walk.bitmask() != 0 {
        // The lanes whose answer is not the bin's first interval walk to
        // it in step, each as the scalar walk does.
        k = k.add(up.to_ones()).sub(down.to_ones());
        let (mut go_up, mut go_down) = (up, down);
        loop {
            let at = first.add(k);
            go_up = go_up
                .and(last.gt(k))
                .and(F8::gather(cdf, at.add(one)).le(u));
            go_down = go_down.and(k.gt(zero)).and(u.lt(F8::gather(cdf, at)));
            if go_up.or(go_down).bitmask() == 0 {
                break;
            }
            k = k.add(go_up.to_ones()).sub(go_down.to_ones());
        }
        let at = first.add(k);
        lo = walk.select(F8::gather(cdf, at), lo);
        hi = walk.select(F8::gather(cdf, at.add(one)), hi);
    }
    // `within_interval`.
    let x = u.sub(lo).div(hi.sub(lo));
    let x = x.lt(F8::splat(0.0)).select(F8::splat(0.0), x);
    let top = F8::splat(0.999_999);
    let x = top.lt(x).select(top, x);
    (k, lo.lt(hi).select(x, F8::splat(0.5)))
}

/// Invert a cumulative table `cdf` (`cdf[0] = 0`, last = 1) at `u`: the
/// interval and the position within it in [0, 1). (The reference for
/// [`Guide::pick`], which gives the same answer faster.)
#[cfg(test)]
fn pick(cdf: &[f32], u: f32) -> (usize, f32) {
    let k = pick_interval(cdf, u);
    (k, within(cdf, k, u))
}

/// The interval of [`pick`]: the last `k < n` with `cdf[k] <= u` (0 if none).
fn pick_interval(cdf: &[f32], u: f32) -> usize {
    let n = cdf.len() - 1;
    // First index with cdf[k] > u, minus one.
    cdf.partition_point(|&c| c <= u).clamp(1, n) - 1
}

/// Where `u` lies within the interval `k` of `cdf`, in [0, 1).
#[inline(always)]
fn within(cdf: &[f32], k: usize, u: f32) -> f32 {
    within_interval(cdf[k], cdf[k + 1], u)
}

/// Where `u` lies within the interval `[a, b)`, in [0, 1) (0.5 if empty).
#[inline(always)]
fn within_interval(a: f32, b: f32, u: f32) -> f32 {
    if b > a {
        ((u - a) / (b - a)).clamp(0.0, 0.999_999)
    } else {
        0.5
    }
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

    /// The guide tables invert the cumulative tables exactly as the binary
    /// search does, on tables with empty intervals (zero-weight cells), a
    /// dominant interval (a sun) and at the bins' edges.
    #[test]
    fn guide_pick_is_the_binary_search() {
        let mut rng = Pcg64::seed_from_u64(11);
        let weights: [&[f32]; 4] = [
            &[1.0; 7],
            &[0.0, 0.0, 3.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0],
            &[
                1e-6, 1e-6, 1e-6, 1.0, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6,
            ],
            &[5.0, 0.0],
        ];
        for w in weights {
            let total: f32 = w.iter().sum();
            let mut cdf = vec![0.0];
            let mut acc = 0.0;
            for x in w {
                acc += x;
                cdf.push(acc / total);
            }
            *cdf.last_mut().unwrap() = 1.0;
            let guide = Guide::new(&cdf);
            let n = w.len();
            let mut us: Vec<f32> = (0..=n).map(|g| g as f32 / n as f32).collect();
            us.extend(cdf.iter().flat_map(|&c| [c, c.next_down(), c.next_up()]));
            us.extend((0..2000).map(|_| rng.random::<f32>()));
            for u in us.into_iter().filter(|u| (0.0..1.0).contains(u)) {
                let (a, b) = (guide.pick(&cdf, u), pick(&cdf, u));
                assert!(
                    a.0 == b.0 && a.1.to_bits() == b.1.to_bits(),
                    "{w:?} u={u}: {a:?} vs {b:?}"
                );
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
