//! Placing a mesh in the scene (Sec. 4.1's world frame, mm): scale, rotate, translate.

use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::scene::mesh::Mesh;

/// Places a mesh in the world: `p' = translation + R (scale * p)` with
/// `R = Rz * Ry * Rx` (XYZ Euler angles in degrees, right-handed, applied X first, then Y, then
/// Z). Deserialises with defaults (scale 1, rotation 0, translation 0) and rejects unknown
/// fields; vectors are written as `[x, y, z]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Transform {
    /// Scale along x, y, z (applied first).
    pub scale: DVec3,
    /// XYZ Euler angles in degrees, applied X then Y then Z.
    pub rotation_deg: DVec3,
    /// Millimetres.
    pub translation: DVec3,
}

impl Default for Transform {
    fn default() -> Self {
        Transform { scale: DVec3::ONE, rotation_deg: DVec3::ZERO, translation: DVec3::ZERO }
    }
}

impl Transform {
    /// Checks that every component is finite and no scale component is zero (which would
    /// flatten the mesh and make normals undefined). `source_name` names the config file.
    pub fn validate(&self, source_name: &str) -> Result<()> {
        for (field, v) in
            [("scale", self.scale), ("rotation_deg", self.rotation_deg), ("translation", self.translation)]
        {
            if !v.is_finite() {
                return Err(Error::invalid(
                    source_name,
                    field,
                    format!("must be finite, got [{}, {}, {}]", v.x, v.y, v.z),
                ));
            }
        }
        if self.scale.cmpeq(DVec3::ZERO).any() {
            return Err(Error::invalid(
                source_name,
                "scale",
                format!("components must be non-zero, got [{}, {}, {}]", self.scale.x, self.scale.y, self.scale.z),
            ));
        }
        Ok(())
    }

    /// The rotation matrix `Rz * Ry * Rx`.
    pub fn rotation(&self) -> DMat3 {
        let r = self.rotation_deg * (std::f64::consts::PI / 180.0);
        DMat3::from_rotation_z(r.z) * DMat3::from_rotation_y(r.y) * DMat3::from_rotation_x(r.x)
    }

    /// Transforms one point.
    pub fn apply_point(&self, p: DVec3) -> DVec3 {
        self.translation + self.rotation() * (self.scale * p)
    }

    /// Transforms positions (scale, rotate, translate) and normals (by the inverse transpose of
    /// the linear part, `R * diag(1 / scale)`, then renormalised). When the scale mirrors the
    /// mesh (odd number of negative components) the triangle winding is reversed so that
    /// geometric normals keep agreeing with the shading normals. Call [`Transform::validate`]
    /// first: a zero scale gives zero normals.
    pub fn apply(&self, mesh: &mut Mesh) {
        let rot = self.rotation();
        let linear = rot * DMat3::from_diagonal(self.scale);
        for p in &mut mesh.positions {
            *p = self.translation + linear * *p;
        }
        if let Some(normals) = &mut mesh.normals {
            let inv_scale = DVec3::ONE / self.scale;
            for n in normals.iter_mut() {
                *n = (rot * (inv_scale * *n)).normalize_or_zero();
            }
        }
        if self.scale.x * self.scale.y * self.scale.z < 0.0 {
            for tri in &mut mesh.triangles {
                tri.swap(1, 2);
            }
        }
    }
}
