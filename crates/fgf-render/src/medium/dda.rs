//! The 3D-DDA (Amanatides–Woo) walk through a lattice of axis-aligned
//! planes over the unit cube of a grid's volume space, shared by the grid
//! medium (its majorant super-voxels, in f32) and the non-exponential
//! macro density (the polynomial pieces of its interpolant, in f64).
//!
//! The planes of axis `k` sit at `(j + offset)/res[k]` for integer `j`:
//! `offset = 0` gives the faces of `res` cells (super-voxels, or the voxels
//! of a `nearest` lookup), `offset = 0.5` the voxel centres between which a
//! `trilinear` lookup is one polynomial (`res + 1` cells, the outer two half
//! a voxel wide). [`walk`] visits the cells a ray crosses inside the unit
//! cube, in order.

use glam::{DVec3, Vec3A};
use std::ops::{Add, ControlFlow, Div, Index, Mul, Neg, Sub};

/// The scalar of a [`Point`]: `f32` or `f64`.
pub trait Real:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    const ZERO: Self;
    const INFINITY: Self;
    fn floor(self) -> Self;
    /// The smaller of the two, ignoring a NaN operand (like `f32::min`).
    fn min(self, other: Self) -> Self;
    /// The larger of the two, ignoring a NaN operand (like `f32::max`).
    fn max(self, other: Self) -> Self;
    fn from_i32(i: i32) -> Self;
    /// Truncating (saturating) conversion, as `as i32`.
    fn to_i32(self) -> i32;
}

/// A 3D point or vector of the walk: glam's `Vec3A` or `DVec3`.
pub trait Point:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Mul<<Self as Point>::S, Output = Self>
    + Index<usize, Output = <Self as Point>::S>
{
    type S: Real;
    const ZERO: Self;
    const ONE: Self;
    fn new(x: Self::S, y: Self::S, z: Self::S) -> Self;
    fn recip(self) -> Self;
    fn min(self, other: Self) -> Self;
    fn max(self, other: Self) -> Self;
    fn min_element(self) -> Self::S;
    fn max_element(self) -> Self::S;
}

macro_rules! impl_point {
    ($v:ty, $s:ty) => {
        impl Real for $s {
            const ZERO: Self = 0.0;
            const INFINITY: Self = <$s>::INFINITY;
            #[inline(always)]
            fn floor(self) -> Self {
                <$s>::floor(self)
            }
            #[inline(always)]
            fn min(self, other: Self) -> Self {
                <$s>::min(self, other)
            }
            #[inline(always)]
            fn max(self, other: Self) -> Self {
                <$s>::max(self, other)
            }
            #[inline(always)]
            fn from_i32(i: i32) -> Self {
                i as $s
            }
            #[inline(always)]
            fn to_i32(self) -> i32 {
                self as i32
            }
        }
        impl Point for $v {
            type S = $s;
            const ZERO: Self = <$v>::ZERO;
            const ONE: Self = <$v>::ONE;
            #[inline(always)]
            fn new(x: $s, y: $s, z: $s) -> Self {
                <$v>::new(x, y, z)
            }
            #[inline(always)]
            fn recip(self) -> Self {
                <$v>::recip(self)
            }
            // Component by component with the scalar rules, which ignore a
            // NaN operand (a zero direction component with the origin on a
            // plane): glam's SIMD `Vec3A::min`/`max` would return it.
            #[inline(always)]
            fn min(self, other: Self) -> Self {
                <$v>::new(
                    Real::min(self.x, other.x),
                    Real::min(self.y, other.y),
                    Real::min(self.z, other.z),
                )
            }
            #[inline(always)]
            fn max(self, other: Self) -> Self {
                <$v>::new(
                    Real::max(self.x, other.x),
                    Real::max(self.y, other.y),
                    Real::max(self.z, other.z),
                )
            }
            #[inline(always)]
            fn min_element(self) -> $s {
                Real::min(self.x, Real::min(self.y, self.z))
            }
            #[inline(always)]
            fn max_element(self) -> $s {
                Real::max(self.x, Real::max(self.y, self.z))
            }
        }
    };
}
impl_point!(Vec3A, f32);
impl_point!(DVec3, f64);

/// The planes `(j + offset)/res[k]` of the module docs.
#[derive(Debug, Clone, Copy)]
pub struct Lattice<S> {
    /// Cells per axis (`offset = 0`), or voxels whose centres are the
    /// planes (`offset = 0.5`).
    pub res: [usize; 3],
    pub offset: S,
}

/// Walk the cells of `lattice` crossed by the ray `o + t d` (unit-cube
/// coordinates, `t` the world parameter) over `[0, t_max]` clipped to the
/// unit cube, calling `f(t0, t1, cell)` for each in order, where `cell[k]`
/// counts the planes of axis `k` below the piece (`0..res` with
/// `offset = 0`, `-1..res` with `offset = 0.5`). Returns the `Break` value
/// if `f` stopped early.
///
/// Successive pieces are contiguous: each starts where the previous ended.
/// Pieces of zero length (the ray crossing two planes at once) are skipped.
#[inline]
pub fn walk<P: Point, B>(
    o: P,
    d: P,
    t_max: P::S,
    lattice: &Lattice<P::S>,
    mut f: impl FnMut(P::S, P::S, [i32; 3]) -> ControlFlow<B>,
) -> ControlFlow<B> {
    let zero = <P::S as Real>::ZERO;
    // Clip to the unit cube.
    let inv = d.recip();
    let ta = (P::ZERO - o) * inv;
    let tb = (P::ONE - o) * inv;
    let t_in = ta.min(tb).max_element().max(zero);
    let t_out = ta.max(tb).min_element().min(t_max);
    if !(t_in < t_out) {
        return ControlFlow::Continue(());
    }
    let r = lattice.res.map(|n| P::S::from_i32(n as i32));
    let res = P::new(r[0], r[1], r[2]);
    let offset = lattice.offset;
    // Cells below the first plane exist only when the planes are offset.
    let lo = if offset > zero { -1 } else { 0 };
    let hi = lattice.res.map(|n| n as i32 - 1);
    let p = (o + d * t_in) * res;
    let mut cell = [0i32; 3];
    let mut step = [0i32; 3];
    let mut t_next = [<P::S as Real>::INFINITY; 3];
    let mut dt = [<P::S as Real>::INFINITY; 3];
    for k in 0..3 {
        cell[k] = (p[k] - offset).floor().to_i32().clamp(lo, hi[k]);
        let plane = |j: i32| ((P::S::from_i32(j) + offset) / res[k] - o[k]) * inv[k];
        if d[k] > zero {
            step[k] = 1;
            t_next[k] = plane(cell[k] + 1);
            dt[k] = inv[k] / res[k];
        } else if d[k] < zero {
            step[k] = -1;
            t_next[k] = plane(cell[k]);
            dt[k] = -inv[k] / res[k];
        }
    }
    let mut t = t_in;
    loop {
        // Axis whose plane comes first.
        let k = if t_next[0] < t_next[1] {
            if t_next[0] < t_next[2] {
                0
            } else {
                2
            }
        } else if t_next[1] < t_next[2] {
            1
        } else {
            2
        };
        let t1 = t_next[k].min(t_out);
        if t1 > t {
            f(t, t1, cell)?;
        }
        if t1 >= t_out {
            return ControlFlow::Continue(());
        }
        t = t1;
        cell[k] += step[k];
        if cell[k] < lo || cell[k] > hi[k] {
            return ControlFlow::Continue(());
        }
        t_next[k] = t_next[k] + dt[k];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{sample_uniform_sphere, Sampler};

    /// Chord length of the ray through the unit cube.
    fn chord(o: Vec3A, d: Vec3A) -> f32 {
        let inv = d.recip();
        let ta = (Vec3A::ZERO - o) * inv;
        let tb = (Vec3A::ONE - o) * inv;
        (ta.max(tb).min_element() - ta.min(tb).max_element().max(0.0)).max(0.0)
    }

    /// The pieces cover the chord through the unit cube contiguously, in
    /// f32 and f64, for cell faces and voxel-centre planes, and each piece
    /// lies in the cell it is reported in.
    #[test]
    fn pieces_are_contiguous_and_in_their_cells() {
        let mut s = Sampler::new(4, 0, 0);
        for _ in 0..500 {
            let o = Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d()) * 3.0 - Vec3A::ONE;
            let d = sample_uniform_sphere(s.next_2d());
            for offset in [0.0, 0.5] {
                let lattice = Lattice {
                    res: [16, 7, 3],
                    offset,
                };
                let mut last: Option<f32> = None;
                let mut total = 0.0;
                let _ = walk(
                    o,
                    d,
                    f32::INFINITY,
                    &lattice,
                    |t0, t1, cell| -> ControlFlow<()> {
                        if let Some(l) = last {
                            assert!((t0 - l).abs() < 1e-5);
                        }
                        last = Some(t1);
                        total += t1 - t0;
                        let mid = o + d * (0.5 * (t0 + t1));
                        for k in 0..3 {
                            let x = mid[k] * lattice.res[k] as f32 - offset;
                            assert!((x - (cell[k] as f32 + 0.5)).abs() <= 0.5 + 1e-4);
                        }
                        ControlFlow::Continue(())
                    },
                );
                assert!(
                    (total - chord(o, d)).abs() < 1e-4,
                    "{total} vs {}",
                    chord(o, d)
                );
                let lattice = Lattice {
                    res: [16, 7, 3],
                    offset: offset as f64,
                };
                let mut total = 0.0;
                let _ = walk(
                    o.as_dvec3(),
                    d.as_dvec3(),
                    f64::INFINITY,
                    &lattice,
                    |t0, t1, _| -> ControlFlow<()> {
                        total += t1 - t0;
                        ControlFlow::Continue(())
                    },
                );
                assert!((total as f32 - chord(o, d)).abs() < 1e-4);
            }
        }
    }
}
