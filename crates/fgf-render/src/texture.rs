//! 2D textures evaluated at a surface point's texture coordinates, with
//! Mitsuba 3's lookups (user docs: [`fgf_scene::xml::textures`]).
//!
//! * `checkerboard`: after `to_uv`, `color0` where the fractional parts of
//!   `u` and `v` fall in the same half of `[0, 1)`, else `color1`.
//! * `bitmap`, `nearest`: the pixel `(⌊u w⌋, ⌊v h⌋)`, row 0 at the top.
//!   `bilinear`: the four pixels around `(u w − ½, v h − ½)` weighted by the
//!   fractional parts (pixel centres sit at half-integers). Pixel indices
//!   outside the image are wrapped first: `repeat` takes them modulo the
//!   size, `mirror` reflects them (`…, 1, 0, 0, 1, …, w−1, w−1, …`),
//!   `clamp` clamps them to the edge.

use crate::spectrum::{from_rgb, Spectrum};
use fgf_scene::{luminance, BitmapFilter, RgbImage, TextureDesc, WrapMode};
use glam::{Affine2, Vec2};
use std::sync::Arc;

#[derive(Debug, Clone)]
pub enum Texture {
    Checkerboard {
        color0: Spectrum,
        color1: Spectrum,
        to_uv: Affine2,
    },
    Bitmap {
        image: Arc<RgbImage>,
        filter: BitmapFilter,
        wrap: WrapMode,
        to_uv: Affine2,
    },
}

/// A pixel index wrapped into `0..n` (`n > 0`).
#[inline]
fn wrap(i: i64, n: i64, mode: WrapMode) -> usize {
    mode.index(i, n)
}

impl Texture {
    pub fn from_desc(d: &TextureDesc) -> Texture {
        match d {
            TextureDesc::Checkerboard {
                color0,
                color1,
                to_uv,
            } => Texture::Checkerboard {
                color0: from_rgb(*color0),
                color1: from_rgb(*color1),
                to_uv: *to_uv,
            },
            TextureDesc::Bitmap {
                image,
                filter,
                wrap,
                to_uv,
            } => Texture::Bitmap {
                image: {
                    // Hits read it anywhere (the scene's copy, shared).
                    crate::huge::advise(&image.data);
                    image.clone()
                },
                filter: *filter,
                wrap: *wrap,
                to_uv: *to_uv,
            },
        }
    }

    /// The texture's colour at texture coordinates `uv`.
    pub fn eval(&self, uv: Vec2) -> Spectrum {
        match self {
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                if checker_first(to_uv, uv) {
                    *color0
                } else {
                    *color1
                }
            }
            Texture::Bitmap {
                image,
                filter,
                wrap: mode,
                to_uv,
            } => {
                let q = to_uv.transform_point2(uv);
                let (w, h) = (image.width as i64, image.height as i64);
                let px = |x: i64, y: i64| {
                    let i = 3 * (wrap(y, h, *mode) * image.width + wrap(x, w, *mode));
                    Spectrum::new(image.data[i], image.data[i + 1], image.data[i + 2])
                };
                let (x, y) = (q.x * w as f32, q.y * h as f32);
                match filter {
                    BitmapFilter::Nearest => px(x.floor() as i64, y.floor() as i64),
                    BitmapFilter::Bilinear => {
                        let (x, y) = (x - 0.5, y - 0.5);
                        let (x0, y0) = (x.floor(), y.floor());
                        let (fx, fy) = (x - x0, y - y0);
                        let (x0, y0) = (x0 as i64, y0 as i64);
                        (px(x0, y0) * (1.0 - fx) + px(x0 + 1, y0) * fx) * (1.0 - fy)
                            + (px(x0, y0 + 1) * (1.0 - fx) + px(x0 + 1, y0 + 1) * fx) * fy
                    }
                }
            }
        }
    }

    /// Mitsuba's `eval_1`, a scalar parameter such as a roughness: the
    /// luminance of a bitmap's value; for a checkerboard the mean of a
    /// colour's channels, where Mitsuba 3.9.1's `eval_1` takes the *other*
    /// colour than `eval` (`color1` where `eval` gives `color0`, checked
    /// against the `mitsuba` package), which fgf follows so that textured
    /// roughness renders as in Mitsuba.
    pub fn eval_1(&self, uv: Vec2) -> f32 {
        match self {
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                let c = if checker_first(to_uv, uv) {
                    color1
                } else {
                    color0
                };
                (c.x + c.y + c.z) / 3.0
            }
            Texture::Bitmap { .. } => luminance(&self.eval(uv).to_array()),
        }
    }
}

/// A checkerboard's square at `uv`: `true` where `color0` lies (the
/// fractional parts of both mapped coordinates on the same side of ½).
#[inline]
fn checker_first(to_uv: &Affine2, uv: Vec2) -> bool {
    let q = to_uv.transform_point2(uv);
    let f = q - q.floor();
    (f.x > 0.5) == (f.y > 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bitmap(filter: BitmapFilter, wrap: WrapMode) -> Texture {
        // 3x2: red green blue / yellow cyan white.
        let data = vec![
            1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, //
            1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0,
        ];
        Texture::Bitmap {
            image: Arc::new(RgbImage {
                width: 3,
                height: 2,
                data,
            }),
            filter,
            wrap,
            to_uv: Affine2::IDENTITY,
        }
    }

    fn close(a: Spectrum, b: [f32; 3]) -> bool {
        (a - Spectrum::from_array(b)).abs().max_element() < 1e-5
    }

    /// Nearest lookups pick the pixel containing (u w, v h), top row first,
    /// with each wrap mode's pixel outside the image.
    #[test]
    fn nearest_lookup_and_wrap_modes() {
        use WrapMode::*;
        let cases: [(Vec2, [[f32; 3]; 3]); 4] = [
            (Vec2::new(0.5, 0.9), [[0.0, 1.0, 1.0]; 3]),
            (Vec2::new(0.9, 0.4), [[0.0, 0.0, 1.0]; 3]),
            // x = 3 (one past the right edge): repeat 0, mirror 2, clamp 2.
            (
                Vec2::new(1.2, 0.3),
                [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]],
            ),
            // x = -1, y = -1: repeat (2, 1), mirror (0, 0), clamp (0, 0).
            (
                Vec2::new(-0.1, -0.2),
                [[1.0, 1.0, 1.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
            ),
        ];
        for (uv, want) in cases {
            for (k, mode) in [Repeat, Mirror, Clamp].into_iter().enumerate() {
                let got = bitmap(BitmapFilter::Nearest, mode).eval(uv);
                assert!(close(got, want[k]), "{uv} {mode:?}: {got}");
            }
        }
    }

    /// Bilinear weights from the closed form: at (0.1, 0.1) the lookup
    /// point is (-0.2, -0.3) in pixel-centre units, so the weights of
    /// pixels x ∈ {-1, 0}, y ∈ {-1, 0} are (0.2, 0.8) × (0.3, 0.7).
    #[test]
    fn bilinear_weights_match_the_closed_form() {
        let px = |x: usize, y: usize| -> [f32; 3] {
            let t = bitmap(BitmapFilter::Nearest, WrapMode::Clamp);
            let c = t.eval(Vec2::new((x as f32 + 0.5) / 3.0, (y as f32 + 0.5) / 2.0));
            c.to_array()
        };
        let mix = |p: [[f32; 3]; 4]| -> [f32; 3] {
            let w = [0.2 * 0.3, 0.8 * 0.3, 0.2 * 0.7, 0.8 * 0.7];
            std::array::from_fn(|c| (0..4).map(|i| w[i] * p[i][c]).sum())
        };
        let uv = Vec2::new(0.1, 0.1);
        let want = [
            (
                WrapMode::Repeat,
                mix([px(2, 1), px(0, 1), px(2, 0), px(0, 0)]),
            ),
            (
                WrapMode::Clamp,
                mix([px(0, 0), px(0, 0), px(0, 0), px(0, 0)]),
            ),
            (
                WrapMode::Mirror,
                mix([px(0, 0), px(0, 0), px(0, 0), px(0, 0)]),
            ),
        ];
        for (mode, w) in want {
            let got = bitmap(BitmapFilter::Bilinear, mode).eval(uv);
            assert!(close(got, w), "{mode:?}: {got} vs {w:?}");
        }
        // The same values the `mitsuba` package gives (scalar_rgb).
        let got = bitmap(BitmapFilter::Bilinear, WrapMode::Repeat).eval(uv);
        assert!(close(got, [0.86, 0.3, 0.2]), "{got}");
        // At a pixel centre bilinear is that pixel.
        let c = Vec2::new(1.5 / 3.0, 0.5 / 2.0);
        let got = bitmap(BitmapFilter::Bilinear, WrapMode::Repeat).eval(c);
        assert!(close(got, [0.0, 1.0, 0.0]), "{got}");
    }

    /// The checkerboard after a `to_uv` of translation, scale and rotation
    /// (the values the `mitsuba` package gives for the same texture).
    #[test]
    fn checkerboard_follows_to_uv() {
        let (s, c) = 30f32.to_radians().sin_cos();
        let rot = Affine2::from_cols_array(&[c, s, -s, c, 0.0, 0.0]);
        let to_uv = Affine2::from_translation(Vec2::new(0.1, 0.2))
            * Affine2::from_scale(Vec2::new(2.0, 3.0))
            * rot;
        let t = Texture::Checkerboard {
            color0: Spectrum::new(1.0, 0.0, 0.0),
            color1: Spectrum::new(0.0, 0.0, 1.0),
            to_uv,
        };
        let red = [(0.3, 0.1), (0.3, 0.3), (0.6, 0.6), (0.6, 0.1)];
        let blue = [(0.1, 0.1), (0.1, 0.3), (0.05, 0.4), (-0.2, 0.1)];
        for (u, v) in red {
            assert_eq!(t.eval(Vec2::new(u, v)).x, 1.0, "({u}, {v})");
        }
        for (u, v) in blue {
            assert_eq!(t.eval(Vec2::new(u, v)).z, 1.0, "({u}, {v})");
        }
        assert!((t.eval_1(Vec2::new(0.3, 0.1)) - 1.0 / 3.0).abs() < 1e-6);
        // eval_1 takes the other colour, as Mitsuba 3.9.1's does (values
        // from the `mitsuba` package for color0 = 0.03, color1 = 0.6).
        let t = Texture::Checkerboard {
            color0: Spectrum::splat(0.03),
            color1: Spectrum::splat(0.6),
            to_uv: Affine2::from_scale(Vec2::new(3.0, 2.0)),
        };
        for (uv, e, e1) in [((0.05, 0.1), 0.03, 0.6), ((0.25, 0.1), 0.6, 0.03)] {
            let uv = Vec2::new(uv.0, uv.1);
            assert!((t.eval(uv).x - e).abs() < 1e-6 && (t.eval_1(uv) - e1).abs() < 1e-6);
        }
    }
}
