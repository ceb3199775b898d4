//! The `perspective` sensor (Mitsuba 3 conventions, `formats.md`): the camera
//! looks down local `+z`, local `+y` is up, film `x` grows toward local `-x`,
//! film `y` downward; `fov` (degrees) spans the film along `fov_axis`. Rays
//! start on the near plane (`near_clip`, measured along the view axis) and
//! end at `far_clip`.

use crate::error::RenderError;
use crate::ray::Ray;
use fgf_scene::{FovAxis, SensorDesc};
use glam::{Affine3A, Vec3A};

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
}
