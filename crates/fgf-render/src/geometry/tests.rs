//! Tests of the geometry: the queries against brute force, area sampling.

use super::query::{disk_root, sphere_roots};
use super::types::{Tri, INDEX_MASK, PAD};
use super::*;
use crate::ray::Ray;
use fgf_scene::TriangleMesh;
use fgf_scene::{GeometryDesc, ShapeDesc};
use glam::{Mat4, Vec3, Vec3A};
use std::sync::Arc;

/// A shape with BSDF 0 and no emitter or media.
fn plain_shape(geometry: GeometryDesc, to_world: Mat4) -> ShapeDesc {
    ShapeDesc {
        name: "shape".into(),
        geometry,
        to_world,
        flip_normals: false,
        bsdf: 0,
        emitter: None,
        interior: None,
        exterior: None,
    }
}

/// A mesh of `positions` and triangles `indices` without normals or
/// texture coordinates.
fn plain_mesh(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> Arc<TriangleMesh> {
    Arc::new(TriangleMesh {
        positions,
        normals: None,
        texcoords: None,
        indices,
    })
}

/// `n` random triangles of about `size` scattered over `[0, 4]³`.
fn triangle_soup(s: &mut crate::math::Sampler, n: u32, size: f32) -> Arc<TriangleMesh> {
    let mut r3 = || Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..n {
        let c = r3() * 4.0;
        for _ in 0..3 {
            positions.push(c + (r3() - Vec3::splat(0.5)) * size);
        }
        indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    plain_mesh(positions, indices)
}

/// The BVH with 4-wide leaf packs finds the same nearest hit as a brute
/// force loop over all triangles (random triangle soup, random rays).
#[test]
fn packed_bvh_matches_brute_force() {
    let mut s = crate::math::Sampler::new(11, 0, 0);
    let r3 = |s: &mut crate::math::Sampler| Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
    let mesh = triangle_soup(&mut s, 300, 0.6);
    let g = Geometry::build(&[plain_shape(GeometryDesc::Mesh(mesh), Mat4::IDENTITY)]).unwrap();
    for _ in 0..2000 {
        let o = r3(&mut s) * 6.0 - Vec3::ONE;
        let d = crate::math::sample_uniform_sphere(s.next_2d());
        let ray = Ray { o: o.into(), d };
        let got = g.intersect(&ray, f32::INFINITY).map(|h| h.t);
        let want = g
            .tris
            .iter()
            .filter_map(|t| intersect_tri(t, o.into(), d, f32::INFINITY).map(|r| r.0))
            .fold(None, |m: Option<f32>, t| Some(m.map_or(t, |m| m.min(t))));
        match (got, want) {
            (None, None) => {}
            (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-5 * (1.0 + b), "{a} vs {b}"),
            other => panic!("{other:?}"),
        }
    }
}

/// The 8-wide tree over a soup of thousands of small triangles finds the
/// nearest hit that testing every leaf pack finds (the same arithmetic, so
/// the same distance and primitive), for random rays, rays along the axes
/// (zero direction components) from the soup's vertices (origins on slab
/// planes), rays in random directions from points on the triangles, and
/// random `t_max`; the all-hits query finds as many hits. The soup lies
/// near the origin, then 20,000 units away, where the rounding of a ray's
/// `o·(1/d)` (10⁵ times its distances to the boxes) and of the triangles'
/// corners must be absorbed by the node test's offsets and the widened
/// boxes (`docs/theory.md` §7.19).
#[test]
fn wide_bvh_matches_brute_force_on_large_soup() {
    wide_bvh_matches_brute_force_at(Vec3::ZERO, 13);
    wide_bvh_matches_brute_force_at(Vec3::new(2.0e4, -1.5e4, 1.2e4), 17);
}

fn wide_bvh_matches_brute_force_at(offset: Vec3, seed: u64) {
    let mut s = crate::math::Sampler::new(seed, 0, 0);
    let r3 = |s: &mut crate::math::Sampler| Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
    let mut mesh = (*triangle_soup(&mut s, 5000, 0.2)).clone();
    for p in &mut mesh.positions {
        *p += offset;
    }
    let vertices = mesh.positions.clone();
    let g = Geometry::build(&[plain_shape(
        GeometryDesc::Mesh(Arc::new(mesh)),
        Mat4::IDENTITY,
    )])
    .unwrap();
    assert!(
        g.bvh.depth_bound() > 2 * 3,
        "the tree should be several levels deep"
    );
    let mut n_hits = 0;
    let vertex = |s: &mut crate::math::Sampler| {
        vertices[(s.next_1d() * vertices.len() as f32) as usize % vertices.len()]
    };
    for k in 0..6000 {
        let (o, d) = match k % 3 {
            0 => {
                let o = r3(&mut s) * 6.0 - Vec3::ONE + offset;
                (o, crate::math::sample_uniform_sphere(s.next_2d()).into())
            }
            1 => {
                let v = vertex(&mut s);
                let mut d = Vec3::ZERO;
                d[k / 3 % 3] = if k / 9 % 2 == 0 { 1.0 } else { -1.0 };
                (v - d * 0.5, d)
            }
            _ => {
                // A point of a triangle (between two of its vertices).
                let i = 3 * (s.next_1d() * 5000.0) as usize % vertices.len();
                let w = s.next_1d();
                let o = vertices[i] * (1.0 - w) + vertices[i + 1] * w;
                (o, crate::math::sample_uniform_sphere(s.next_2d()).into())
            }
        };
        let ray = Ray {
            o: o.into(),
            d: d.into(),
        };
        let t_max = if k % 3 == 0 {
            f32::INFINITY
        } else {
            4.0 * s.next_1d()
        };
        // Brute force: every pack, nearest first, first lane on ties.
        let od = super::pack::splat_ray(&ray);
        let mut want: Option<(f32, u32)> = None;
        let mut count = 0;
        for (i, pack) in g.packs.iter().enumerate() {
            let (mask, t, _, _) = pack.hits::<false>(od.0, od.1, t_max);
            for l in 0..super::bvh::PACK {
                if mask & (1 << l) != 0 {
                    count += 1;
                    if want.is_none_or(|w| t.to_array()[l] < w.0) {
                        want = Some((t.to_array()[l], g.prims[super::bvh::PACK * i + l]));
                    }
                }
            }
        }
        n_hits += count;
        let got = g.intersect(&ray, t_max).map(|h| (h.t, h.prim));
        match (got, want) {
            (Some(a), Some(b)) => assert!(a.0 == b.0, "offset {offset}, ray {k}: {a:?} vs {b:?}"),
            (a, b) => assert_eq!(a, b, "offset {offset}, ray {k}: {o} {d}"),
        }
        let mut all = 0;
        g.for_each_hit(&ray, t_max, |_, _, _, _| {
            all += 1;
            true
        });
        assert_eq!(all, count, "ray {k}");
    }
    assert!(n_hits > 3000, "too few hits to test anything: {n_hits}");
}

/// A scene of every primitive kind (a triangle soup, cubes and
/// rectangles as parallelograms, spheres, disks): the nearest, the two
/// nearest and the all-hits queries agree with brute force over the
/// primitives, for random rays and random segment lengths.
#[test]
fn queries_match_brute_force_on_mixed_primitives() {
    use glam::Quat;
    let mut s = crate::math::Sampler::new(12, 0, 0);
    let r3 = |s: &mut crate::math::Sampler| Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
    let mut shapes = Vec::new();
    let mut push =
        |geometry: GeometryDesc, to_world: Mat4| shapes.push(plain_shape(geometry, to_world));
    push(
        GeometryDesc::Mesh(triangle_soup(&mut s, 40, 0.8)),
        Mat4::IDENTITY,
    );
    for _ in 0..6 {
        let rot = Quat::from_axis_angle(
            (r3(&mut s) - Vec3::splat(0.5)).normalize(),
            3.0 * s.next_1d(),
        );
        let m =
            Mat4::from_scale_rotation_translation(0.2 + r3(&mut s) * 0.6, rot, r3(&mut s) * 4.0);
        push(GeometryDesc::Cube, m);
        push(
            GeometryDesc::Rectangle,
            m * Mat4::from_translation(Vec3::Z * 0.3),
        );
        push(
            GeometryDesc::Disk,
            m * Mat4::from_translation(Vec3::X * 0.5),
        );
        let c = r3(&mut s) * 4.0;
        push(
            GeometryDesc::Sphere {
                center: c,
                radius: 0.1 + 0.5 * s.next_1d(),
            },
            Mat4::IDENTITY,
        );
    }
    let g = Geometry::build(&shapes).unwrap();
    assert!(g.tris.iter().any(|t| t.quad) && !g.spheres.is_empty() && !g.disks.is_empty());
    let mut n_hits = 0usize;
    for _ in 0..3000 {
        let o = r3(&mut s) * 6.0 - Vec3::ONE;
        let d = crate::math::sample_uniform_sphere(s.next_2d());
        let ray = Ray { o: o.into(), d };
        let t_max = if s.next_1d() < 0.5 {
            f32::INFINITY
        } else {
            6.0 * s.next_1d()
        };
        let mut want: Vec<(f32, u32)> = Vec::new();
        for t in &g.tris {
            if let Some((th, _, _)) = intersect_tri(t, o.into(), d, t_max) {
                want.push((th, t.shape));
            }
        }
        for sp in &g.spheres {
            for th in sphere_roots(sp, &ray) {
                if th > 0.0 && th < t_max {
                    want.push((th, sp.shape));
                }
            }
        }
        for dk in &g.disks {
            let th = disk_root(dk, &ray);
            if th > 0.0 && th < t_max {
                want.push((th, dk.shape));
            }
        }
        want.sort_by(|a, b| a.0.total_cmp(&b.0));
        n_hits += want.len();
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * (1.0 + b);
        let near = g.intersect(&ray, t_max).map(|h| h.t);
        match (near, want.first()) {
            (None, None) => {}
            (Some(a), Some(b)) => assert!(close(a, b.0), "nearest {a} vs {}", b.0),
            other => panic!("nearest: {other:?}"),
        }
        let (h1, h2) = g.intersect2(&ray, t_max);
        assert_eq!(h1.map(|h| h.t), near);
        match (h2.map(|r| g.make_hit(&ray, r).t), want.get(1)) {
            (None, None) => {}
            (Some(a), Some(b)) => assert!(close(a, b.0), "second {a} vs {}", b.0),
            other => panic!("second: {other:?}"),
        }
        let mut all = Vec::new();
        assert!(g.for_each_hit(&ray, t_max, |_, shape, t, n| {
            assert!((n.length() - 1.0).abs() < 1e-4);
            all.push((t, shape));
            true
        }));
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert_eq!(all.len(), want.len());
        for (a, b) in all.iter().zip(&want) {
            assert!(close(a.0, b.0) && a.1 == b.1, "{a:?} vs {b:?}");
        }
        // Stopping at the first hit visits exactly one.
        if !want.is_empty() {
            let mut visits = 0;
            assert!(!g.for_each_hit(&ray, t_max, |_, _, _, _| {
                visits += 1;
                false
            }));
            assert_eq!(visits, 1);
        }
    }
    assert!(n_hits > 1000, "too few hits to test anything: {n_hits}");
}

/// A scene that is one pack (a cube, two rectangles: the reference media
/// scenes' shapes) answers the queries of the nearest hit, of the two
/// nearest and of every crossing without the walk
/// ([`Geometry::lone_pack`]), and gives the walk's answers bit for bit
/// (the crossings in the same order):
/// random rays from outside and inside the cube, rays aimed at its edges
/// and corners (where two faces meet at the same distance, and the tie
/// rule decides), rays in the planes of its faces, random `t_max`.
#[test]
fn lone_pack_gives_the_walks_hits() {
    let mut s = crate::math::Sampler::new(21, 0, 0);
    let r3 = |s: &mut crate::math::Sampler| Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
    let cube = Mat4::from_scale_rotation_translation(
        Vec3::splat(0.5),
        glam::Quat::from_rotation_y(0.3),
        Vec3::new(0.0, 0.75, 0.0),
    );
    let shapes = [
        plain_shape(GeometryDesc::Cube, cube),
        plain_shape(
            GeometryDesc::Rectangle,
            Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2)
                * Mat4::from_scale(Vec3::splat(4.0)),
        ),
        plain_shape(
            GeometryDesc::Rectangle,
            Mat4::from_translation(Vec3::new(-2.5, 2.0, 0.5)) * Mat4::from_scale(Vec3::splat(0.25)),
        ),
    ];
    let mut g = Geometry::build(&shapes).unwrap();
    assert!(g.lone_pack, "8 parallelograms should be one pack");
    let bits =
        |r: Option<HitRecord>| r.map(|HitRecord((p, t, u, v))| (p, [t, u, v].map(f32::to_bits)));
    let hit_bits =
        |h: Option<Hit>| h.map(|h| (h.prim, h.t.to_bits(), h.p.to_array().map(f32::to_bits)));
    let corner = |s: &mut crate::math::Sampler| {
        let c = (r3(s) * 2.0).floor() * 2.0 - Vec3::ONE;
        cube.transform_point3(c)
    };
    let (mut ties, mut seconds) = (0, 0);
    for k in 0..20_000 {
        let (o, target) = match k % 4 {
            // From anywhere toward anywhere.
            0 => (
                r3(&mut s) * 6.0 - Vec3::splat(3.0),
                r3(&mut s) * 2.0 - Vec3::ONE,
            ),
            // From inside the cube.
            1 => (
                cube.transform_point3(r3(&mut s) - Vec3::splat(0.5)),
                r3(&mut s),
            ),
            // Toward a point on an edge, or a corner.
            2 => {
                let (a, b) = (corner(&mut s), corner(&mut s));
                let u = if s.next_1d() < 0.5 { 0.0 } else { s.next_1d() };
                (r3(&mut s) * 6.0 - Vec3::splat(3.0), a + (b - a) * u)
            }
            // Along an edge of the cube (in the planes of two faces).
            _ => {
                let (a, b) = (corner(&mut s), corner(&mut s));
                (a + (a - b) * (1.0 + s.next_1d()), b)
            }
        };
        let d = (target - o).normalize();
        if !d.is_finite() {
            continue;
        }
        let ray = Ray {
            o: o.into(),
            d: d.into(),
        };
        let t_max = if k % 3 == 0 {
            1.0 + 4.0 * s.next_1d()
        } else {
            f32::INFINITY
        };
        // Every crossing, in the order visited, and the first alone.
        let crossings = |g: &Geometry, stop: bool| {
            let mut seen = Vec::new();
            let open = g.for_each_hit(&ray, t_max, |p, shape, t, n| {
                seen.push((p, shape, t.to_bits(), n.to_array().map(f32::to_bits)));
                !stop
            });
            (open, seen)
        };
        g.lone_pack = true;
        let (a1, a2) = g.intersect2(&ray, t_max);
        let a0 = g.intersect(&ray, t_max);
        let (a3, a4) = (crossings(&g, false), crossings(&g, true));
        g.lone_pack = false;
        let (b1, b2) = g.intersect2(&ray, t_max);
        let b0 = g.intersect(&ray, t_max);
        assert_eq!(
            a3,
            crossings(&g, false),
            "crossings, ray {ray:?}, t_max {t_max}"
        );
        assert_eq!(
            a4,
            crossings(&g, true),
            "first crossing, ray {ray:?}, t_max {t_max}"
        );
        assert_eq!(
            hit_bits(a0),
            hit_bits(b0),
            "nearest alone, ray {ray:?}, t_max {t_max}"
        );
        assert_eq!(
            hit_bits(a1),
            hit_bits(b1),
            "nearest, ray {ray:?}, t_max {t_max}"
        );
        assert_eq!(bits(a2), bits(b2), "second, ray {ray:?}, t_max {t_max}");
        if let (Some(h), Some(HitRecord((_, t, _, _)))) = (a1, a2) {
            seconds += 1;
            ties += usize::from(h.t == t);
        }
    }
    // The rays hit twice often, and at ties now and then.
    assert!(
        seconds > 5_000 && ties > 20,
        "seconds {seconds}, ties {ties}"
    );
}

/// Parallelograms sample points uniformly over their whole area, and a
/// cube's area is that of its six faces.
#[test]
fn cube_area_and_sampling() {
    let cube = plain_shape(
        GeometryDesc::Cube,
        Mat4::from_scale(Vec3::new(1.0, 2.0, 3.0)),
    );
    let g = Geometry::build(&[cube]).unwrap();
    // Faces 2x4, 4x6, 2x6 (two of each).
    assert!((g.areas[0] - 2.0 * (8.0 + 24.0 + 12.0)).abs() < 1e-4);
    let mut s = crate::math::Sampler::new(5, 0, 0);
    let n = 40_000;
    let mut on_top_far_corner = 0;
    for _ in 0..n {
        let ps = g.sample_shape(0, s.next_1d(), s.next_2d());
        // On the surface of the box, normal pointing out of the face.
        let q = Vec3::from(ps.p) / Vec3::new(1.0, 2.0, 3.0);
        assert!((q.abs().max_element() - 1.0).abs() < 1e-5);
        let axis = (0..3)
            .max_by(|&a, &b| q[a].abs().total_cmp(&q[b].abs()))
            .unwrap();
        let mut face_n = Vec3::ZERO;
        face_n[axis] = q[axis].signum();
        assert!(
            (Vec3::from(ps.n) - face_n).length() < 1e-6,
            "{:?} at {:?}",
            ps.n,
            ps.p
        );
        if ps.n.y > 0.5 && ps.p.x > 0.0 && ps.p.z > 0.0 {
            on_top_far_corner += 1;
        }
    }
    // The quarter x, z > 0 of the +y face (2 x 6): area 3 of 88; 4 SE.
    let p = 3.0 / 88.0;
    let se = (p * (1.0 - p) / n as f64).sqrt();
    let got = on_top_far_corner as f64 / n as f64;
    assert!((got - p).abs() < 4.0 * se, "{got} vs {p}");
}

/// Möller–Trumbore, one triangle or parallelogram; returns `(t, u, v)`
/// with `0 < t < t_max`.
/// The reference the 4-wide [`TriPack::hits`] is tested against.
fn intersect_tri(tri: &Tri, o: Vec3A, d: Vec3A, t_max: f32) -> Option<(f32, f32, f32)> {
    let pvec = d.cross(tri.e2);
    let det = tri.e1.dot(pvec);
    if det == 0.0 {
        return None;
    }
    let inv_det = 1.0 / det;
    let tvec = o - tri.v0;
    let u = tvec.dot(pvec) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qvec = tvec.cross(tri.e1);
    let v = d.dot(qvec) * inv_det;
    if v < 0.0 || (if tri.quad { v > 1.0 } else { u + v > 1.0 }) {
        return None;
    }
    let t = tri.e2.dot(qvec) * inv_det;
    if t > 0.0 && t < t_max {
        Some((t, u, v))
    } else {
        None
    }
}

/// Texture coordinates at hits on every kind of shape, against the values
/// the `mitsuba` package (3.9.1, `scalar_rgb`) reports for the same rays
/// (`SurfaceInteraction3f.uv` of `Scene.ray_intersect`).
#[test]
fn texture_coordinates_match_mitsuba() {
    let down = Vec3::new(0.0, 0.0, -1.0);
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let uvs = vec![
        glam::Vec2::new(0.1, 0.2),
        glam::Vec2::new(0.9, 0.3),
        glam::Vec2::new(0.2, 0.7),
    ];
    let mesh = |texcoords| {
        GeometryDesc::Mesh(Arc::new(TriangleMesh {
            positions: tri.to_vec(),
            normals: None,
            texcoords,
            indices: vec![[0, 1, 2]],
        }))
    };
    let rotated = Mat4::from_translation(Vec3::new(1.3, 1.3, 0.0))
        * Mat4::from_rotation_x(60f32.to_radians());
    let sphere = GeometryDesc::Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    };
    // (shape, to_world, ray origin, direction, Mitsuba's uv)
    let cases: Vec<(GeometryDesc, Mat4, Vec3, Vec3, [f32; 2])> = vec![
        (
            GeometryDesc::Rectangle,
            Mat4::IDENTITY,
            Vec3::new(0.5, -0.25, 1.0),
            down,
            [0.75, 0.375],
        ),
        (
            GeometryDesc::Disk,
            Mat4::IDENTITY,
            Vec3::new(0.5, 0.25, 1.0),
            down,
            [0.559017, 0.0737918],
        ),
        (
            GeometryDesc::Disk,
            Mat4::IDENTITY,
            Vec3::new(-0.5, -0.25, 1.0),
            down,
            [0.559017, 0.573792],
        ),
        (
            sphere.clone(),
            Mat4::IDENTITY,
            Vec3::new(0.3, 0.4, 5.0),
            down,
            [0.147584, 0.166667],
        ),
        (
            sphere.clone(),
            Mat4::IDENTITY,
            Vec3::new(-0.3, -0.4, 5.0),
            down,
            [0.647584, 0.166667],
        ),
        (
            sphere.clone(),
            rotated,
            Vec3::new(1.5, 1.6, 5.0),
            down,
            [0.217236, 0.433773],
        ),
        (
            sphere,
            rotated,
            Vec3::new(1.0, 1.1, 5.0),
            down,
            [0.313806, 0.279111],
        ),
        (
            GeometryDesc::Cube,
            Mat4::IDENTITY,
            Vec3::new(0.3, 0.2, 5.0),
            down,
            [0.6, 0.65],
        ),
        (
            GeometryDesc::Cube,
            Mat4::IDENTITY,
            Vec3::new(0.3, 0.2, -5.0),
            -down,
            [0.4, 0.65],
        ),
        (
            GeometryDesc::Cube,
            Mat4::IDENTITY,
            Vec3::new(5.0, 0.3, 0.2),
            -Vec3::X,
            [0.65, 0.4],
        ),
        (
            GeometryDesc::Cube,
            Mat4::IDENTITY,
            Vec3::new(-5.0, 0.3, 0.2),
            Vec3::X,
            [0.65, 0.6],
        ),
        (
            GeometryDesc::Cube,
            Mat4::IDENTITY,
            Vec3::new(0.3, 5.0, 0.2),
            -Vec3::Y,
            [0.35, 0.4],
        ),
        (
            GeometryDesc::Cube,
            Mat4::IDENTITY,
            Vec3::new(0.3, -5.0, 0.2),
            Vec3::Y,
            [0.6, 0.65],
        ),
        // A mesh's uvs interpolated by the barycentrics (0.25, 0.5); without
        // uvs, the barycentrics themselves.
        (
            mesh(Some(uvs)),
            Mat4::IDENTITY,
            Vec3::new(0.25, 0.5, 1.0),
            down,
            [0.35, 0.475],
        ),
        (
            mesh(None),
            Mat4::IDENTITY,
            Vec3::new(0.25, 0.5, 1.0),
            down,
            [0.25, 0.5],
        ),
    ];
    for (k, (g, m, o, d, want)) in cases.into_iter().enumerate() {
        let geom = Geometry::build(&[plain_shape(g, m)]).unwrap();
        let h = geom
            .intersect(
                &Ray {
                    o: o.into(),
                    d: d.into(),
                },
                f32::INFINITY,
            )
            .expect("a hit");
        let uv = geom.uv(&h);
        assert!(
            (uv.x - want[0]).abs() < 2e-5 && (uv.y - want[1]).abs() < 2e-5,
            "case {k}: uv {uv} against Mitsuba's {want:?}"
        );
    }
}

/// The tangent-oriented shading frame (`frame.rs`): orthonormal with
/// `t = n × s`, and `s` along the parameterisation's `∂p/∂u` where it is
/// known in closed form: a rectangle's local x, a sphere's azimuth
/// direction, a disk's radial direction (the values themselves are
/// checked against Mitsuba by `tests/test_anisotropic.py`).
#[test]
fn shading_frame_follows_dp_du() {
    let rot = Mat4::from_rotation_y(0.4) * Mat4::from_rotation_x(-0.3);
    let shapes = [
        plain_shape(
            GeometryDesc::Rectangle,
            rot * Mat4::from_scale(Vec3::new(2.0, 0.5, 1.0)),
        ),
        plain_shape(
            GeometryDesc::Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
            },
            Mat4::from_translation(Vec3::new(5.0, 0.0, 0.0)) * rot,
        ),
        plain_shape(
            GeometryDesc::Disk,
            Mat4::from_translation(Vec3::new(-5.0, 0.0, 0.0)) * rot,
        ),
    ];
    let g = Geometry::build(&shapes).unwrap();
    let (m3, inv) = (
        glam::Mat3::from_mat4(rot),
        glam::Mat3::from_mat4(rot).inverse(),
    );
    let mut s = crate::math::Sampler::new(5, 0, 0);
    let mut checked = [0; 3];
    for _ in 0..600 {
        let target = Vec3::new([0.0, 5.0, -5.0][(s.next_1d() * 3.0) as usize % 3], 0.0, 0.0)
            + (Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) - 0.5) * 0.8;
        let o = target + Vec3::from(crate::math::sample_uniform_sphere(s.next_2d())) * 3.0;
        let Some(h) = g.intersect(
            &Ray {
                o: o.into(),
                d: (target - o).normalize().into(),
            },
            f32::INFINITY,
        ) else {
            continue;
        };
        let f = g.shading_frame(&h);
        assert!((f.s.length() - 1.0).abs() < 1e-5 && f.s.dot(f.n).abs() < 1e-5);
        assert!((f.t - f.n.cross(f.s)).length() < 1e-5 && f.n == h.ns);
        let want = match h.shape {
            0 => m3 * Vec3::X,
            1 => {
                let l = inv * (Vec3::from(h.p) - Vec3::new(5.0, 0.0, 0.0));
                m3 * Vec3::new(-l.y, l.x, 0.0)
            }
            _ => {
                let l = inv * (Vec3::from(h.p) - Vec3::new(-5.0, 0.0, 0.0));
                m3 * Vec3::new(l.x, l.y, 0.0)
            }
        };
        let want = (Vec3A::from(want) - f.n * f.n.dot(want.into())).normalize();
        assert!(
            (f.s - want).length() < 1e-3,
            "shape {}: s {} vs {want}",
            h.shape,
            f.s
        );
        checked[h.shape as usize] += 1;
    }
    assert!(checked.iter().all(|&c| c > 50), "{checked:?}");
}

/// A `k` × `k` grid of quads, each two triangles with shared edges, as a
/// gently curved height field over `[0, 4]²` (y up).
pub(crate) fn height_field(k: u32) -> Arc<TriangleMesh> {
    let mut positions = Vec::new();
    for i in 0..=k {
        for j in 0..=k {
            let (x, z) = (4.0 * i as f32 / k as f32, 4.0 * j as f32 / k as f32);
            positions.push(Vec3::new(x, 0.3 * (1.7 * x).sin() * (1.3 * z).cos(), z));
        }
    }
    let v = |i: u32, j: u32| i * (k + 1) + j;
    let mut indices = Vec::new();
    for i in 0..k {
        for j in 0..k {
            indices.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            indices.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    plain_mesh(positions, indices)
}

/// The beam query of a bundle of nearly parallel rays (the camera rays of
/// one pixel: directions within a small cone, origins on a near plane)
/// gives every ray the nearest hit its own query gives: the same distance
/// and primitive.
/// Bundles of 1 to 16 rays, narrow and wide, with finite and infinite
/// limits, over a triangle soup, a height field with shared edges, and the
/// height field with every triangle twice (every hit a tie, which both
/// queries must break toward the least primitive id, the first copy); and
/// bundles whose directions change sign along an axis, which form no beam
/// and are traced ray by ray.
#[test]
fn beam_gives_each_ray_its_own_nearest_hit() {
    use super::bvh::{Beam, BEAM};
    use super::types::INDEX_MASK;
    let mut s = crate::math::Sampler::new(23, 0, 0);
    let soup = triangle_soup(&mut s, 5000, 0.2);
    let mut twice = (*height_field(64)).clone();
    let n_tris = twice.indices.len() as u32;
    twice.indices.extend_from_within(..);
    let mesh = |m: Arc<TriangleMesh>| {
        Geometry::build(&[plain_shape(GeometryDesc::Mesh(m), Mat4::IDENTITY)]).unwrap()
    };
    let scenes = [mesh(soup), mesh(height_field(96)), mesh(Arc::new(twice))];
    let (mut beams, mut hits, mut ties) = (0, 0, 0);
    for (gi, g) in scenes.iter().enumerate() {
        for k in 0..3000 {
            let n = 1 + k % BEAM;
            let eye =
                Vec3A::new(2.0, 3.0, -1.5) + Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d());
            let target = Vec3A::new(4.0 * s.next_1d(), 0.5 * s.next_1d(), 4.0 * s.next_1d());
            let axis = (target - eye).normalize();
            // Pixel-sized cones (1e-3 rad), a few wide ones (0.1 rad), and
            // every 7th bundle aimed so that x changes sign across it.
            let spread = if k % 5 == 0 { 0.1 } else { 1e-3 };
            let axis = if k % 7 == 3 {
                Vec3A::new(0.0, axis.y, axis.z).normalize()
            } else {
                axis
            };
            let rays: Vec<Ray> = (0..n)
                .map(|_| {
                    let jitter = Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d()) - 0.5;
                    let d = (axis + spread * jitter).normalize();
                    Ray {
                        o: eye + 0.01 * d,
                        d,
                    }
                })
                .collect();
            let t_max: Vec<f32> = (0..n)
                .map(|j| {
                    if (k + j) % 3 == 0 {
                        3.0 + 2.0 * s.next_1d()
                    } else {
                        1e4
                    }
                })
                .collect();
            let inv: Vec<Vec3A> = rays.iter().map(|r| r.d.recip()).collect();
            let mixed = rays.iter().any(|r| r.d.x < 0.0) && rays.iter().any(|r| r.d.x > 0.0);
            let beam = Beam::new(&rays, &inv);
            assert!(
                !(mixed && beam.is_some()),
                "scene {gi}, bundle {k}: mixed signs form a beam"
            );
            beams += (beam.is_some() && n > 1) as u32;
            let mut got = [None; BEAM];
            g.intersect_beam(&rays, &t_max, &mut got[..n]);
            for j in 0..n {
                let want = g.intersect(&rays[j], t_max[j]).map(|h| (h.t, h.prim));
                let got = got[j].map(|h| (h.t, h.prim));
                assert_eq!(got, want, "scene {gi}, bundle {k}, ray {j}");
                hits += got.is_some() as u32;
                if let (2, Some((_, prim))) = (gi, got) {
                    assert!(
                        prim & INDEX_MASK < n_tris,
                        "bundle {k}, ray {j}: the second copy"
                    );
                    ties += 1;
                }
            }
        }
    }
    assert!(beams > 4000, "too few bundles formed beams: {beams}");
    assert!(hits > 10_000, "too few hits to test anything: {hits}");
    assert!(ties > 3000, "too few ties to test the rule: {ties}");
}

/// Hits read their vertices, normals and texture coordinates through the
/// per-triangle corners and the shared vertex arrays: with several meshes
/// (offsets into those arrays), meshes with and without normals and uvs,
/// fewer normals than vertices, a mirrored transform and flipped normals,
/// every hit gets what its own mesh's data say.
#[test]
fn hits_read_their_own_mesh_vertex_data() {
    let mut s = crate::math::Sampler::new(5, 0, 0);
    let quad = |z: f32| {
        vec![
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z),
            Vec3::new(1.0, 1.0, z),
            Vec3::new(-1.0, 1.0, z),
        ]
    };
    let idx = vec![[0, 1, 2], [0, 2, 3]];
    let normals: Vec<Vec3> = (0..4)
        .map(|k| Vec3::new(0.1 * k as f32, -0.2, 1.0).normalize())
        .collect();
    let uvs: Vec<Vec2> = (0..4)
        .map(|k| Vec2::new(0.25 * k as f32, 1.0 - 0.5 * k as f32))
        .collect();
    let mesh = |z, n: Option<Vec<Vec3>>, t: Option<Vec<Vec2>>| {
        GeometryDesc::Mesh(Arc::new(TriangleMesh {
            positions: quad(z),
            normals: n,
            texcoords: t,
            indices: idx.clone(),
        }))
    };
    let mirror = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    let mut flipped = plain_shape(mesh(2.0, Some(normals[..3].to_vec()), None), Mat4::IDENTITY);
    flipped.flip_normals = true;
    let shapes = [
        plain_shape(mesh(0.0, None, None), Mat4::IDENTITY),
        plain_shape(mesh(1.0, Some(normals.clone()), Some(uvs.clone())), mirror),
        flipped,
        plain_shape(mesh(3.0, None, Some(uvs.clone())), Mat4::IDENTITY),
    ];
    let g = Geometry::build(&shapes).unwrap();
    // The same scene with hits made from the corners (as for large meshes)
    // rather than read from the `Tri` records: the same bits.
    let mut from_corners = Geometry::build(&shapes).unwrap();
    assert!(g.small);
    from_corners.small = false;
    let bits = |h: &Hit| {
        let v = |a: Vec3A| a.to_array().map(f32::to_bits);
        (
            h.t.to_bits(),
            v(h.p),
            v(h.n),
            v(h.ns),
            h.shape,
            h.prim,
            h.bary.map(f32::to_bits),
        )
    };
    for _ in 0..400 {
        let (x, y) = (1.8 * s.next_1d() - 0.9, 1.8 * s.next_1d() - 0.9);
        for (k, z) in [0.0f32, 1.0, 2.0, 3.0].into_iter().enumerate() {
            let ray = Ray {
                o: Vec3A::new(x, y, z - 0.5),
                d: Vec3A::Z,
            };
            let h = g.intersect(&ray, 1.0).expect("the quad in front");
            let h2 = from_corners
                .intersect(&ray, 1.0)
                .expect("the quad in front");
            assert_eq!(bits(&h), bits(&h2), "shape {k}");
            assert_eq!(h.shape, k as u32);
            assert!((h.p - Vec3A::new(x, y, z)).length() < 1e-5);
            // Barycentrics of the hit triangle, from the mesh's own data.
            let [u, v] = h.bary;
            // (Shape 1 is mirrored in x: its local point is (-x, y).)
            let xl = if k == 1 { -x } else { x };
            let t = idx[if xl >= y { 0 } else { 1 }];
            let at = |a: [Vec3; 3]| (1.0 - u - v) * a[0] + u * a[1] + v * a[2];
            let corner = |data: &[Vec3]| [0, 1, 2].map(|c| data[t[c] as usize]);
            // Mirrored (1) and flipped (2): facing -z.
            let want_n = if k == 1 || k == 2 { -Vec3::Z } else { Vec3::Z };
            assert!(
                (Vec3::from(h.n) - want_n).length() < 1e-6,
                "shape {k}: n {:?}",
                h.n
            );
            let want_ns = match k {
                1 => {
                    let m = Mat3::from_mat4(mirror).inverse().transpose();
                    at(corner(&normals).map(|n| (m * n).normalize())).normalize()
                }
                // Normals for the first three vertices only: triangles
                // using the fourth have none, as before.
                2 if t.iter().all(|&i| i < 3) => -at(corner(&normals)).normalize(),
                _ => want_n,
            };
            assert!(
                (Vec3::from(h.ns) - want_ns).length() < 1e-5,
                "shape {k}: ns {:?} vs {want_ns:?}",
                h.ns
            );
            let want_uv = match k {
                1 | 3 => {
                    let c = [0, 1, 2].map(|c| uvs[t[c] as usize]);
                    (1.0 - u - v) * c[0] + u * c[1] + v * c[2]
                }
                _ => Vec2::new(u, v),
            };
            assert!((g.uv(&h) - want_uv).length() < 1e-6, "shape {k}: uv");
        }
    }
    // Parallelograms (a cube, a mirrored rectangle): both ways the same.
    let shapes = [
        plain_shape(
            GeometryDesc::Cube,
            Mat4::from_scale_rotation_translation(
                Vec3::new(0.5, 0.7, 0.3),
                glam::Quat::from_rotation_y(0.4),
                Vec3::new(0.2, 0.1, 0.0),
            ),
        ),
        plain_shape(
            GeometryDesc::Rectangle,
            Mat4::from_translation(Vec3::new(0.0, 0.0, -1.5)) * mirror,
        ),
    ];
    let g = Geometry::build(&shapes).unwrap();
    let mut from_corners = Geometry::build(&shapes).unwrap();
    from_corners.small = false;
    let mut n_hits = 0;
    for _ in 0..2000 {
        let o = crate::math::sample_uniform_sphere(s.next_2d()) * 3.0;
        let d = (Vec3A::new(s.next_1d(), s.next_1d(), s.next_1d()) - 0.5 - o).normalize();
        let ray = Ray { o, d };
        let (h, h2) = (
            g.intersect(&ray, f32::INFINITY),
            from_corners.intersect(&ray, f32::INFINITY),
        );
        assert_eq!(h.map(|h| bits(&h)), h2.map(|h| bits(&h)));
        n_hits += usize::from(h.is_some());
    }
    assert!(n_hits > 1000, "{n_hits} hits");
}

/// A mesh of many triangles keeps no `Tri` records: every query makes
/// them from the corners. Its hits, crossings, recovered hits, `∂p/∂u`,
/// samples and area all agree with the triangles computed here from the
/// mesh's own data (flipped normals included), and a parallelogram keeps
/// its flag among them.
#[test]
fn large_meshes_answer_from_their_corners() {
    let mesh = height_field(48);
    let mut field = plain_shape(GeometryDesc::Mesh(mesh.clone()), Mat4::IDENTITY);
    field.flip_normals = true;
    // A unit square at y = 1 above the field (which stays below 0.3),
    // facing up.
    let rect = plain_shape(
        GeometryDesc::Rectangle,
        Mat4::from_translation(Vec3::new(2.0, 1.0, 2.0))
            * Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2)
            * Mat4::from_scale(Vec3::splat(0.5)),
    );
    let g = Geometry::build(&[field, rect]).unwrap();
    assert!(mesh.indices.len() > Geometry::SMALL);
    assert!(!g.small && g.tris.is_empty());
    let last = g.corners.len() - 1;
    assert!(g.corners[last].quad() && !g.corners[..last].iter().any(|c| c.quad()));
    // The mesh's triangle `i`: corners, and its flipped unit normal.
    let corners = |i: usize| mesh.indices[i].map(|k| Vec3A::from(mesh.positions[k as usize]));
    let normal = |i: usize| {
        let [a, b, c] = corners(i);
        -(b - a).cross(c - a).normalize()
    };
    let close = |a: Vec3A, b: Vec3A| (a - b).length() < 1e-5;
    let area: f64 = (0..mesh.indices.len())
        .map(|i| {
            let [a, b, c] = corners(i).map(|p| p.as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    assert!(
        (f64::from(g.areas[0]) - area).abs() < 1e-5 * area,
        "{} vs {area}",
        g.areas[0]
    );
    assert!((g.areas[1] - 1.0).abs() < 1e-6, "{}", g.areas[1]);
    let mut s = crate::math::Sampler::new(31, 0, 0);
    let (mut n_hits, mut n_rect) = (0, 0);
    for _ in 0..2000 {
        let o = Vec3A::new(4.0 * s.next_1d(), 2.0, 4.0 * s.next_1d());
        let d = (Vec3A::new(4.0 * s.next_1d(), -1.0, 4.0 * s.next_1d()) - o).normalize();
        let ray = Ray { o, d };
        let hit = g.intersect(&ray, f32::INFINITY);
        let mut crossings = 0;
        let open = g.for_each_hit(&ray, f32::INFINITY, |p, shape, t, n| {
            crossings += 1;
            let i = (p & INDEX_MASK) as usize;
            if shape == 0 {
                assert!(close(n, normal(i)), "crossing {i}: {n}");
                assert!(close(ray.at(t), g.hit_at(&ray, p, t).p));
            }
            true
        });
        assert!(open);
        assert_eq!(g.occluded(&ray, f32::INFINITY), crossings > 0);
        // Where the ray crosses y = 1: in the square or not.
        let q = ray.at((1.0 - o.y) / d.y);
        let in_square = (q.x - 2.0).abs() < 0.5 && (q.z - 2.0).abs() < 0.5;
        let Some(h) = hit else {
            panic!("a ray down onto the field hits nothing")
        };
        assert_eq!(h.shape == 1, in_square, "{q}");
        if h.shape == 1 {
            n_rect += 1;
            assert!(close(h.n, Vec3A::Y) && close(h.p, q), "{} at {}", h.n, h.p);
            continue;
        }
        n_hits += 1;
        let i = (h.prim & INDEX_MASK) as usize;
        let [a, b, c] = corners(i);
        let [u, v] = h.bary;
        assert!(close(h.p, a + u * (b - a) + v * (c - a)));
        assert!(close(h.n, normal(i)) && close(h.ns, h.n));
        assert!(close(g.dp_du(&h), b - a));
        let again = g.hit_at(&ray, h.prim, h.t);
        assert!((again.bary[0] - u).abs() < 1e-3 && (again.bary[1] - v).abs() < 1e-3);
        let ps = g.sample_shape_hit(0, s.next_1d(), s.next_2d());
        let i = (ps.prim & INDEX_MASK) as usize;
        let [a, b, c] = corners(i);
        let [u, v] = ps.bary;
        assert!(u >= 0.0 && v >= 0.0 && u + v <= 1.0);
        assert!(close(ps.p, a + u * (b - a) + v * (c - a)) && close(ps.n, normal(i)));
    }
    assert!(
        n_hits > 1000 && n_rect > 10,
        "{n_hits} mesh hits, {n_rect} rectangle hits"
    );
}

/// A scene with more primitives than a reference can index (here one
/// mesh of 2^20 faces shared by 1,025 shapes) is refused with an error that
/// names the count and the limit, before anything is allocated for it.
#[test]
fn too_many_primitives_is_an_error() {
    let mesh = plain_mesh(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]; 1 << 20]);
    let shapes: Vec<ShapeDesc> = (0..1025)
        .map(|_| plain_shape(GeometryDesc::Mesh(mesh.clone()), Mat4::IDENTITY))
        .collect();
    match Geometry::build(&shapes) {
        Err(crate::RenderError::InvalidScene(m)) => {
            assert!(m.contains("1074790400 primitives"), "{m}");
            assert!(m.contains("at most 1073741824"), "{m}");
        }
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("a scene of 2^30 + 2^20 faces was accepted"),
    }
}

/// Faces with no area (a repeated vertex, collinear vertices) are dropped
/// from the geometry, the others kept in order with their own vertices and
/// areas: in a first mesh and in one after it, whose records follow.
#[test]
fn degenerate_faces_are_dropped_in_order() {
    let positions = vec![
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(2.0, 3.0, 0.0),
    ];
    // Areas 0.5, none, none, 1.5; then none, 3.
    let first = plain_mesh(
        positions.clone(),
        vec![[0, 1, 2], [0, 0, 1], [0, 1, 3], [1, 3, 4]],
    );
    let second = plain_mesh(positions, vec![[1, 1, 1], [0, 3, 4]]);
    let shapes = [
        plain_shape(GeometryDesc::Mesh(first), Mat4::IDENTITY),
        plain_shape(GeometryDesc::Mesh(second), Mat4::IDENTITY),
    ];
    let g = Geometry::build(&shapes).unwrap();
    // The second mesh's vertices follow the first's five.
    let want = [[0, 1, 2], [1, 3, 4], [5, 8, 9]];
    let got: Vec<[u32; 3]> = g.corners.iter().map(|c| c.v).collect();
    assert_eq!(got, want);
    assert_eq!(g.tris.len(), 3);
    for (t, c) in g.tris.iter().zip(&g.corners) {
        let p = |i: u32| Vec3A::from(g.positions[i as usize]);
        assert_eq!(t.v0, p(c.v[0]));
        assert_eq!(t.v0 + t.e1, p(c.v[1]));
        assert_eq!(t.v0 + t.e2, p(c.v[2]));
        assert_eq!(t.n, Vec3A::Z);
    }
    assert_eq!(g.areas[..2], [2.0, 3.0]);
    match (&g.sampling[0], &g.sampling[1]) {
        (ShapeSampling::Tris { first: 0, cdf: a }, ShapeSampling::Tris { first: 2, cdf: b }) => {
            assert_eq!(a[..], [0.25, 1.0]);
            assert_eq!(b[..], [1.0]);
        }
        other => panic!("sampling {other:?}"),
    }
    // Every primitive reference names a kept triangle, each once.
    let mut tris: Vec<u32> = g
        .prims
        .iter()
        .filter(|&&p| p != PAD)
        .map(|&p| p & INDEX_MASK)
        .collect();
    tris.sort_unstable();
    assert_eq!(tris, [0, 1, 2]);
}
