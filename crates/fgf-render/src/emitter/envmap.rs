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
    /// `(W + 1) × H` vertex radiances, row-major.
    data: Vec<Spectrum>,
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
    col_guide: Vec<Guide>,
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
    /// Per bin: the interval `k` and `cdf[k]`, `cdf[k + 1]`.
    start: Vec<(u32, f32, f32)>,
}

impl Guide {
    fn new(cdf: &[f32]) -> Guide {
        let n = cdf.len() - 1;
        let start = (0..n)
            .map(|g| {
                let k = pick_interval(cdf, g as f32 / n as f32);
                (k as u32, cdf[k], cdf[k + 1])
            })
            .collect();
        Guide { start }
    }

    /// [`pick`] on `cdf`, the table this guide was made from.
    #[inline(always)]
    fn pick(&self, cdf: &[f32], u: f32) -> (usize, f32) {
        let n = cdf.len() - 1;
        let g = bin_index(u * n as f32, n);
        // The bin's start is exact for `u` at its lower end; rounding of
        // `u · n` may put `u` just below it, hence the walk down as well.
        let (k0, lo, hi) = self.start[g];
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
                data.push(Spectrum::new(img.data[i], img.data[i + 1], img.data[i + 2]));
            }
        }
        let (nx, ny) = (w, h - 1);
        let mut weight = vec![0f64; nx * ny];
        for j in 0..ny {
            let sin_t = ((j as f64 + 0.5) / ny as f64 * std::f64::consts::PI).sin();
            for i in 0..nx {
                let v = |x: usize, y: usize| luminance(data[y * (w + 1) + x]) as f64;
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
        let col_guide = col_cdf.chunks_exact(nx + 1).map(Guide::new).collect();
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
            col_guide,
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
        let at = |x: usize, y: usize| self.data[y * row + x];
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
        let (i, fu) = self.col_guide[j].pick(&self.col_cdf[j * (nx + 1)..(j + 1) * (nx + 1)], u[0]);
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
}
