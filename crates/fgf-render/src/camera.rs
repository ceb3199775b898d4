//! The `perspective` sensor (Mitsuba 3 conventions, `formats.md`): the camera
//! looks down local `+z`, local `+y` is up, film `x` grows toward local `-x`,
//! film `y` downward; `fov` (degrees) spans the film along `fov_axis`. Rays
//! start on the near plane (`near_clip`, measured along the view axis) and
//! end at `far_clip`.

use crate::error::RenderError;
use crate::lanes::F8;
use crate::math::mul_normalize8;
use crate::ray::Ray;
use fgf_scene::{FovAxis, SensorDesc};
use glam::{Affine3A, Mat3, Vec3A};

#[derive(Debug, Clone)]
pub struct Camera {
    to_world: Affine3A,
    /// tan of the half field of view along film x and y.
    tan_x: f32,
    tan_y: f32,
    /// Mitsuba's principal point offset, in pixels (0 leaves the
    /// arithmetic, and so the image, bit-identical to a camera without it).
    pp: [f32; 2],
    pub width: u32,
    pub height: u32,
    /// `width` and `height` as f32, converted once rather than per ray.
    size: [f32; 2],
    near: f32,
    far: f32,
}

impl Camera {
    pub fn new(s: &SensorDesc) -> Result<Camera, RenderError> {
        if s.width == 0 || s.height == 0 {
            return Err(RenderError::InvalidScene(format!(
                "film size {}x{}: width and height must be >= 1",
                s.width, s.height
            )));
        }
        if !(s.fov > 0.0 && s.fov < 180.0) {
            return Err(RenderError::InvalidScene(format!(
                "sensor fov = {}; must be in (0, 180) degrees",
                s.fov
            )));
        }
        if !(s.near_clip > 0.0 && s.far_clip > s.near_clip) {
            return Err(RenderError::InvalidScene(format!(
                "sensor near_clip = {}, far_clip = {}; need 0 < near_clip < far_clip",
                s.near_clip, s.far_clip
            )));
        }
        let aspect = s.width as f32 / s.height as f32;
        let t = (0.5 * s.fov.to_radians()).tan();
        let along_x = match s.fov_axis {
            FovAxis::X => true,
            FovAxis::Y => false,
            FovAxis::Smaller => s.width <= s.height,
            FovAxis::Larger => s.width >= s.height,
        };
        let (tan_x, tan_y) = if along_x {
            (t, t / aspect)
        } else {
            (t * aspect, t)
        };
        Ok(Camera {
            to_world: Affine3A::from_mat4(s.to_world),
            tan_x,
            tan_y,
            pp: [
                s.principal_point[0] * s.width as f32,
                s.principal_point[1] * s.height as f32,
            ],
            width: s.width,
            height: s.height,
            size: [s.width as f32, s.height as f32],
            near: s.near_clip,
            far: s.far_clip,
        })
    }

    /// The ray through film position `(fx, fy)` in pixels from the top-left
    /// corner, with its maximum distance (the far plane).
    pub fn generate_ray(&self, fx: f32, fy: f32) -> (Ray, f32) {
        // Mitsuba adds the principal point offset to the film position
        // (as a fraction of the film) before the projection.
        let nx = 2.0 * (fx + self.pp[0]) / self.size[0] - 1.0;
        let ny = 2.0 * (fy + self.pp[1]) / self.size[1] - 1.0;
        // The point on the local z = 1 plane; its distance `len` from the
        // eye scales the near and far planes (given along the view axis)
        // into distances along the ray.
        let local = Vec3A::new(-nx * self.tan_x, -ny * self.tan_y, 1.0);
        let len = local.length();
        let o = self.to_world.translation;
        let d = self.to_world.transform_vector3a(local).normalize();
        let t_near = self.near * len;
        (
            Ray {
                o: o + d * t_near,
                d,
            },
            (self.far - self.near) * len,
        )
    }

    /// [`Self::generate_ray`] of eight film positions (lanes of `fx`,
    /// `fy`): the rays' origins and directions (x, y, z) and their limits,
    /// each lane with the bits of the scalar function's ray, by the same
    /// operations in the same order. Eight at a time, a ray's divisions
    /// and square roots cost an eighth of an instruction each.
    #[inline(always)]
    pub(crate) fn generate_rays8(&self, fx: F8, fy: F8) -> ([F8; 3], [F8; 3], F8) {
        let film = |f: F8, a: usize| {
            let two = F8::splat(2.0);
            two.mul(f.add(F8::splat(self.pp[a])))
                .div(F8::splat(self.size[a]))
                .sub(F8::splat(1.0))
        };
        let (nx, ny) = (film(fx, 0), film(fy, 1));
        let one = F8::splat(1.0);
        let local = [
            nx.neg().mul(F8::splat(self.tan_x)),
            ny.neg().mul(F8::splat(self.tan_y)),
            one,
        ];
        // |local|, as glam sums the squares: (x² + y²) + z².
        let len = local[0]
            .mul(local[0])
            .add(local[1].mul(local[1]))
            .add(one.mul(one))
            .sqrt();
        let d = mul_normalize8(Mat3::from(self.to_world.matrix3), local);
        let t_near = F8::splat(self.near).mul(len);
        let t = self.to_world.translation;
        let o = [0, 1, 2].map(|c| F8::splat(t[c]).add(d[c].mul(t_near)));
        (o, d, F8::splat(self.far - self.near).mul(len))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fgf_scene::FilterDesc;
    use glam::Mat4;

    fn sensor(fov_axis: FovAxis, w: u32, h: u32) -> SensorDesc {
        SensorDesc {
            // Mitsuba lookat from (0,0,5) to the origin, up +y: left = +x... see formats.md.
            to_world: Mat4::from_cols(
                glam::Vec4::new(-1.0, 0.0, 0.0, 0.0),
                glam::Vec4::new(0.0, 1.0, 0.0, 0.0),
                glam::Vec4::new(0.0, 0.0, -1.0, 0.0),
                glam::Vec4::new(0.0, 0.0, 5.0, 1.0),
            ),
            fov: 90.0,
            fov_axis,
            principal_point: [0.0, 0.0],
            near_clip: 0.01,
            far_clip: 100.0,
            width: w,
            height: h,
            rfilter: FilterDesc::Box,
            spp: 1,
            seed: 0,
            medium: None,
        }
    }

    /// The film centre looks down the view axis; the right edge of the film
    /// (x = width) is at the fov's half angle toward world +x (not mirrored);
    /// the top edge is toward +y.
    #[test]
    fn rays_follow_mitsuba_film_conventions() {
        let c = Camera::new(&sensor(FovAxis::X, 200, 100)).unwrap();
        let (r, _) = c.generate_ray(100.0, 50.0);
        assert!((r.d - Vec3A::new(0.0, 0.0, -1.0)).length() < 1e-6);
        let (r, _) = c.generate_ray(200.0, 50.0);
        // fov 90 along x: 45° to the right.
        assert!(
            (r.d - Vec3A::new(1.0, 0.0, -1.0).normalize()).length() < 1e-5,
            "{:?}",
            r.d
        );
        let (r, _) = c.generate_ray(100.0, 0.0);
        // Aspect 2: tan(half fov y) = 0.5, toward +y at the top.
        assert!(
            (r.d - Vec3A::new(0.0, 0.5, -1.0).normalize()).length() < 1e-5,
            "{:?}",
            r.d
        );
        // fov along y on the same film: the top edge is at 45°.
        let c = Camera::new(&sensor(FovAxis::Y, 200, 100)).unwrap();
        let (r, _) = c.generate_ray(100.0, 0.0);
        assert!((r.d - Vec3A::new(0.0, 1.0, -1.0).normalize()).length() < 1e-5);
        // smaller = y for a landscape film.
        let c = Camera::new(&sensor(FovAxis::Smaller, 200, 100)).unwrap();
        let (r2, _) = c.generate_ray(100.0, 0.0);
        assert!((r.d - r2.d).length() < 1e-6);
    }

    /// Each lane of [`Camera::generate_rays8`] has the bits of the scalar
    /// ray, for a rotated and offset camera with a principal point, over
    /// the film, its edges and past them.
    #[test]
    fn rays8_are_generate_ray() {
        use rand::{Rng, SeedableRng};
        let mut s = sensor(FovAxis::Y, 317, 123);
        s.to_world = Mat4::look_at_rh(
            glam::Vec3::new(0.3, 2.0, 4.6),
            glam::Vec3::new(-0.2, 0.5, 0.1),
            glam::Vec3::Y,
        )
        .inverse();
        s.principal_point = [0.013, -0.021];
        s.fov = 37.5;
        let c = Camera::new(&s).unwrap();
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let bits = |v: Vec3A| v.to_array().map(f32::to_bits);
        for round in 0..5_000 {
            let mut fx: [f32; 8] = std::array::from_fn(|_| rng.random::<f32>() * 340.0 - 10.0);
            let mut fy: [f32; 8] = std::array::from_fn(|_| rng.random::<f32>() * 140.0 - 10.0);
            if round == 0 {
                (fx[0], fy[0], fx[1], fy[1]) = (0.0, 0.0, 317.0f32.next_down(), 123.0);
            }
            let (o, d, t) = c.generate_rays8(F8::from_array(fx), F8::from_array(fy));
            let (o, d, t) = (o.map(F8::to_array), d.map(F8::to_array), t.to_array());
            for l in 0..8 {
                let (r, t_max) = c.generate_ray(fx[l], fy[l]);
                let lane = |a: [[f32; 8]; 3]| Vec3A::new(a[0][l], a[1][l], a[2][l]);
                assert_eq!(bits(lane(o)), bits(r.o), "({}, {})", fx[l], fy[l]);
                assert_eq!(bits(lane(d)), bits(r.d), "({}, {})", fx[l], fy[l]);
                assert_eq!(t[l].to_bits(), t_max.to_bits());
            }
        }
    }
}
