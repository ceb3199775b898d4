use fgf_render::geometry::{Geometry, Ray};
use fgf_render::scene::desc::*;
use glam::{Mat4, Vec3};
#[test]
fn dbg() {
    let m = Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2) * Mat4::from_scale(Vec3::splat(5.0));
    let ground = ShapeDesc { name: "g".into(), geometry: GeometryDesc::Rectangle, to_world: m, flip_normals: false, bsdf: 0, emitter: None, interior: None, exterior: None };
    let dm = Mat4::from_translation(Vec3::new(0.3, 2.5, 0.3)) * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2) * Mat4::from_scale(Vec3::splat(0.4));
    let disk = ShapeDesc { name: "d".into(), geometry: GeometryDesc::Disk, to_world: dm, flip_normals: false, bsdf: 0, emitter: None, interior: None, exterior: None };
    let g = Geometry::build(&[ground, disk]).unwrap();
    let o = Vec3::new(0.5, 1.8, 4.2);
    let d = Vec3::new(-0.480598, -0.1737596, -0.859554).normalize();
    let h = g.intersect(&Ray { o, d }, f32::INFINITY).unwrap();
    println!("hit t {} p {:?} n {:?} shape {}", h.t, h.p, h.n, h.shape);
    let q = Vec3::new(0.3, 2.5, 0.3);
    let wi = (q - h.p).normalize();
    let o2 = fgf_render::geometry::offset_point(h.p, h.n, wi);
    let h2 = g.intersect(&Ray { o: o2, d: wi }, (q - o2).length() - 1e-3);
    println!("shadow {:?}", h2);
}
