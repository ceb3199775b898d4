//! Triangle meshes for the `obj` and `ply` shapes.
//!
//! * OBJ ([`obj`]): our own reader (faces fan-triangulated, one index per vertex so
//!   that positions and normals line up; every `o`/`g` group is merged into
//!   one mesh, as Mitsuba does).
//! * PLY ([`ply`]): our own small reader for `ascii`, `binary_little_endian` and
//!   `binary_big_endian`. `ply-rs` (the only PLY crate) has had no release
//!   since 2020, and a reader this size lets us refuse hostile headers
//!   (element counts larger than the file could hold) before allocating.
//!   It reads `vertex` (`x y z`, optional `nx ny nz` and texture
//!   coordinates `u v`, `s t` or `texture_u texture_v`) and `face`
//!   (`vertex_indices` or `vertex_index` lists; n-gons fan-triangulated);
//!   other elements and properties are skipped.
//!
//! * Mitsuba's `serialized` ([`serialized`]): versions 3 and 4, zlib streams
//!   read with `flate2`, any mesh of the file by `shape_index`.
//!
//! Normals are kept only if every vertex has one; they are normalised.
//! Texture coordinates likewise (an OBJ's `vt` as `(u, 1 - v)`, as
//! Mitsuba 3 stores them, so that `v = 0` is an image's top row).
//!
//! Meshes without vertex normals get Mitsuba's smooth ones from
//! [`smooth_vertex_normals`] (user docs: [`super::shapes`]). Mitsuba
//! (`Mesh::recompute_vertex_normals`, after Thürmer and Wüthrich 1998)
//! weights each unit face normal by the face's angle at the vertex, on the
//! world-space positions; angle weighting is not invariant under
//! non-uniform scale or shear, so we compute in world space too and store
//! `normalize(Mᵀ n_world)`, which the renderer's `M^{-T}` maps back onto
//! `n_world`.

mod obj;
mod ply;
mod serialized;

pub(crate) use obj::load_obj;
pub(crate) use ply::load_ply;
pub(crate) use serialized::load_serialized;

use super::document::XNode;
use crate::desc::TriangleMesh;
use crate::error::{SceneError, SceneErrorKind};
use crate::validate::{mesh_problem, MeshProblem};
use glam::{Mat3, Mat4, Vec2, Vec3};
use std::path::Path;

/// The error of a `what` file (`PLY`, `OBJ`...) at `path` that cannot be
/// opened or read.
fn io_error(fnode: &XNode, path: &Path, what: &str, e: std::io::Error) -> SceneError {
    fnode.err_kind(
        SceneErrorKind::Io,
        format!("cannot read {what} file '{}': {e}", path.display()),
    )
}

pub(super) fn read_file(fnode: &XNode, path: &Path, what: &str) -> Result<Vec<u8>, SceneError> {
    fgf_io::read_regular(path).map_err(|e| io_error(fnode, path, what, e))
}

/// The regular file at `path`, opened, and its size.
pub(super) fn open_file(
    fnode: &XNode,
    path: &Path,
    what: &str,
) -> Result<(std::fs::File, u64), SceneError> {
    fgf_io::open_regular(path).map_err(|e| io_error(fnode, path, what, e))
}

/// Check and normalise a mesh (by the rules of [`mesh_problem`]); `Err` is
/// a message about the file's content.
pub(super) fn finish(
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    texcoords: Option<Vec<Vec2>>,
    indices: Vec<[u32; 3]>,
) -> Result<TriangleMesh, String> {
    let mut m = TriangleMesh {
        positions,
        normals,
        texcoords,
        indices,
    };
    match mesh_problem(&m) {
        Some(p @ MeshProblem::Normal(_)) => Err(format!(
            "{p} (use face_normals=\"true\" to ignore the file's normals)"
        )),
        Some(p) => Err(p.to_string()),
        None => {
            for v in m.normals.iter_mut().flatten() {
                *v /= v.length();
            }
            Ok(m)
        }
    }
}

/// Angle between two unit vectors, accurate for small and large angles
/// (`acos` of the dot product loses half the digits near 0 and π): the
/// chord `|a − b|` gives the angle through `2 asin(|a − b| / 2)`, and the
/// supplement is used past π/2, as Mitsuba's `unit_angle` does.
fn unit_angle(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) >= 0.0 {
        2.0 * (0.5 * (b - a).length()).asin()
    } else {
        std::f32::consts::PI - 2.0 * (0.5 * (a + b).length()).asin()
    }
}

/// Smooth vertex normals of a mesh that has none, computed as Mitsuba 3.9
/// does (see the module docs): angle-weighted unit face normals in world
/// space, degenerate faces skipped, `(1, 0, 0)` for a zero sum. Returns
/// local-space unit normals `normalize(Mᵀ n_world)`, which the renderer's
/// inverse-transpose maps back onto `n_world`.
pub(crate) fn smooth_vertex_normals(
    positions: &[Vec3],
    indices: &[[u32; 3]],
    to_world: &Mat4,
) -> Vec<Vec3> {
    // f32 throughout, like Mitsuba's scalar loader, so that the results
    // agree to float rounding.
    let world: Vec<Vec3> = positions
        .iter()
        .map(|&p| to_world.transform_point3(p))
        .collect();
    let mut sums = vec![Vec3::ZERO; positions.len()];
    for t in indices {
        let v = [
            world[t[0] as usize],
            world[t[1] as usize],
            world[t[2] as usize],
        ];
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let len2 = n.length_squared();
        // A zero (or non-finite) cross product: no orientation, no weight.
        if !(len2 > 0.0 && len2.is_finite()) {
            continue;
        }
        let n = n / len2.sqrt();
        for j in 0..3 {
            let d0 = (v[(j + 1) % 3] - v[j]).normalize();
            let d1 = (v[(j + 2) % 3] - v[j]).normalize();
            sums[t[j] as usize] += n * unit_angle(d0, d1);
        }
    }
    let to_local = Mat3::from_mat4(*to_world).transpose();
    sums.into_iter()
        .map(|s| {
            let len = s.length();
            // Mitsuba's placeholder for a vertex without a usable face.
            let nw = if len != 0.0 && len.is_finite() {
                s / len
            } else {
                Vec3::X
            };
            (to_local * nw).normalize_or(Vec3::X)
        })
        .collect()
}

/// A reader for the tests of the mesh readers: it gives at most `step`
/// bytes a call, as a pipe or a slow disk may, so that values, tokens and
/// lines straddle every refill; and with [`Trickle::interrupted_every`],
/// every `k`-th call fails with `Interrupted` (to be retried).
#[cfg(test)]
pub(super) struct Trickle<'a> {
    b: &'a [u8],
    step: usize,
    interrupt: usize,
    calls: usize,
}

#[cfg(test)]
impl<'a> Trickle<'a> {
    pub(super) fn new(b: &'a [u8], step: usize) -> Self {
        Trickle {
            b,
            step,
            interrupt: 0,
            calls: 0,
        }
    }

    pub(super) fn interrupted_every(self, k: usize) -> Self {
        Trickle {
            interrupt: k,
            ..self
        }
    }
}

#[cfg(test)]
impl std::io::Read for Trickle<'_> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        self.calls += 1;
        if self.interrupt > 0 && self.calls % self.interrupt == 0 {
            return Err(std::io::ErrorKind::Interrupted.into());
        }
        let n = self.step.min(out.len()).min(self.b.len());
        out[..n].copy_from_slice(&self.b[..n]);
        self.b = &self.b[n..];
        Ok(n)
    }
}
