//! The camera: an orbit around the scene's bounds, perspective with depth in [0, 1].

use glam::{Mat4, Vec3};
use serde::Serialize;

use crate::{Aabb, OitError, Scene};

/// Where the camera sits on its orbit, and how wide it sees.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct View {
    /// Degrees around the vertical axis; 0 looks down −z from +z.
    pub azimuth: f32,
    /// Degrees above the horizontal plane.
    pub elevation: f32,
    /// Vertical field of view in degrees.
    pub fov: f32,
}

impl Default for View {
    fn default() -> Self {
        View { azimuth: 30.0, elevation: 20.0, fov: 45.0 }
    }
}

/// A fitted camera: view and projection matrices (right-handed, depth in [0, 1]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Camera {
    /// World to view.
    pub view: Mat4,
    /// View to clip (`Mat4::perspective_rh`).
    pub proj: Mat4,
    /// The eye position in world space.
    pub eye: Vec3,
    /// The unit viewing direction in world space.
    pub forward: Vec3,
    /// Near plane distance.
    pub near: f32,
    /// Far plane distance.
    pub far: f32,
}

impl Camera {
    /// Orbits around `bounds` at `view`'s angles, framing the bounding sphere, with near/far fitted
    /// to it.
    pub fn orbit(bounds: &Aabb, view: View, aspect: f32) -> Result<Camera, OitError> {
        if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
            return Err(OitError::InvalidScene("scene bounds are empty or not finite".into()));
        }
        Camera::orbit_sphere(bounds.center(), bounds.radius(), bounds.radius(), view, aspect)
    }

    /// Orbits around `scene`, framing the tightest sphere about its bounds' centre that holds every
    /// vertex (tighter than the box's corners, so the scene fills the frame and depth precision is
    /// not spent on empty space).
    pub fn orbit_scene(scene: &Scene, view: View, aspect: f32) -> Result<Camera, OitError> {
        let bounds = scene.bounds();
        if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
            return Err(OitError::InvalidScene("scene bounds are empty or not finite".into()));
        }
        let center = bounds.center();
        let mut radius2 = 0.0f32;
        for inst in &scene.instances {
            let mesh = scene.instance_parts(inst).1;
            for &p in &mesh.positions {
                radius2 = radius2.max(inst.transform.transform_point3(p).distance_squared(center));
            }
        }
        Camera::orbit_sphere(center, radius2.sqrt(), bounds.radius(), view, aspect)
    }

    /// Orbits around a sphere, framing the sphere of `radius`, with near/far holding the larger
    /// sphere of `depth_radius` (the box's corners: so every bounding box the bucket techniques
    /// rasterize for their depth range lies between near and far, never clipped by far).
    pub fn orbit_sphere(
        center: Vec3,
        radius: f32,
        depth_radius: f32,
        view: View,
        aspect: f32,
    ) -> Result<Camera, OitError> {
        if !(view.azimuth.is_finite() && view.elevation.is_finite()) {
            return Err(OitError::InvalidSettings("azimuth and elevation must be finite".into()));
        }
        if !(0.5..=179.0).contains(&view.fov) {
            return Err(OitError::InvalidSettings(format!(
                "fov {} is out of range: use a vertical field of view from 0.5 to 179 degrees",
                view.fov
            )));
        }
        if !(aspect.is_finite() && aspect > 0.0) {
            return Err(OitError::InvalidSettings("aspect ratio must be positive".into()));
        }
        let too_large = || {
            OitError::InvalidScene(format!(
                "the scene is too large to frame: its bounding sphere (centre {center}, radius {radius:e}) \
                 puts the camera beyond f32's range; keep coordinates within ±{:e}",
                crate::Mesh::MAX_COORDINATE
            ))
        };
        if !center.is_finite() || !radius.is_finite() || !depth_radius.is_finite() {
            return Err(too_large());
        }
        let radius = radius.max(1e-3 * center.length()).max(1e-6);
        let vhalf = view.fov.to_radians() * 0.5;
        let half = vhalf.min((vhalf.tan() * aspect).atan());
        let distance = radius / half.sin() * 1.05;
        let (az, el) = (view.azimuth.to_radians(), view.elevation.clamp(-89.0, 89.0).to_radians());
        let dir = Vec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
        let eye = center + dir * distance;
        let depth_radius = depth_radius.max(radius);
        let near = (distance - depth_radius * 1.01).max(distance * 1e-3);
        let far = distance + depth_radius * 1.01;
        let camera = Camera::look_at(eye, center, view.fov, aspect, near, far);
        if !(camera.view_proj().is_finite() && (eye - center).length_squared().is_finite()) {
            return Err(too_large());
        }
        Ok(camera)
    }

    /// A camera looking from `eye` at `target` (y up), with explicit planes.
    pub fn look_at(eye: Vec3, target: Vec3, fov_deg: f32, aspect: f32, near: f32, far: f32) -> Camera {
        let forward = (target - eye).normalize_or(Vec3::NEG_Z);
        let up = if forward.cross(Vec3::Y).length_squared() < 1e-8 { Vec3::Z } else { Vec3::Y };
        let view = Mat4::look_at_rh(eye, target, up);
        let proj = Mat4::perspective_rh(fov_deg.to_radians(), aspect, near, far);
        Camera { view, proj, eye, forward, near, far }
    }

    /// World to clip.
    pub fn view_proj(&self) -> Mat4 {
        self.proj * self.view
    }

    /// View-space distance (positive, along the viewing axis) of an NDC depth in [0, 1].
    pub fn linear_depth(&self, ndc_z: f32) -> f32 {
        // perspective_rh maps z_view = -n to 0 and -f to 1: ndc = f(z + n) / (z (n - f)) with z < 0.
        let (n, f) = (self.near, self.far);
        n * f / (f - ndc_z * (f - n))
    }

    /// [`Camera::linear_depth`] in f64 (the reference's translucency).
    pub fn linear_depth_f64(&self, ndc_z: f32) -> f64 {
        let (n, f, z) = (f64::from(self.near), f64::from(self.far), f64::from(ndc_z));
        n * f / (f - z * (f - n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fov_range_is_inclusive_as_documented() {
        // `--fov` help: "0.5 to 179"; both ends were refused by a strict comparison
        let unit = Aabb { min: Vec3::ZERO, max: Vec3::ONE };
        for fov in [0.5, 45.0, 179.0] {
            let c = Camera::orbit(&unit, View { fov, ..View::default() }, 1.0).unwrap();
            assert!(c.view_proj().is_finite() && c.near > 0.0 && c.near < c.far, "fov {fov}");
        }
        for fov in [0.499, 179.001, 0.0, -45.0, f32::NAN, f32::INFINITY] {
            let e = Camera::orbit(&unit, View { fov, ..View::default() }, 1.0).unwrap_err().to_string();
            assert!(e.contains("from 0.5 to 179"), "{fov}: {e}");
        }
    }

    #[test]
    fn largest_scene_frames_finitely_and_larger_is_named_too_large() {
        // at the narrowest fov the eye stands ~240 radii away: still finite at MAX_COORDINATE
        let m = crate::Mesh::MAX_COORDINATE;
        let big = Aabb { min: Vec3::splat(-m), max: Vec3::splat(m) };
        let c = Camera::orbit(&big, View { fov: 0.5, ..View::default() }, 1.0).unwrap();
        assert!(c.view_proj().is_finite() && c.eye.is_finite());
        // finite boxes whose radius, or the eye's distance, overflows: "too large", not "not
        // finite"
        for max in [Vec3::new(1e37, 1e37, 0.0), Vec3::new(1e36, 0.0, 0.0)] {
            let huge = Aabb { min: Vec3::ZERO, max };
            let e = Camera::orbit(&huge, View { fov: 0.5, ..View::default() }, 1.0).unwrap_err().to_string();
            assert!(e.contains("too large") && !e.contains("not finite"), "{e}");
        }
    }
}
