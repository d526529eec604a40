//! The camera: an orbit around the scene's bounds, perspective with depth in [0, 1].
//!
//! The orbit fits any scene whose bounding radius lies between [`Camera::MIN_RADIUS`] and
//! [`Camera::MAX_RADIUS`], and refuses the rest with a message saying which end was passed. The
//! fit is computed in f64 in units of the scene's radius about its centre, and the view matrix
//! carries the scale (`look_at · scale(1/r) · translate(−centre)`): clip coordinates are then of
//! order 1 at every scale, so a scene at 10⁻³⁰ or 10³⁰ draws the same fragments as at 1 (the
//! same bits when the scale is a power of two), where a world-space eye would square distances of
//! 10⁻⁶⁰ (0 in f32) or 10⁶⁰ (infinite).

use glam::{DMat4, DVec3, Mat4, Vec3};
use serde::Serialize;

use crate::{Aabb, OitError, Scene};

/// Where the camera sits on its orbit, how wide it sees, and (optionally) where it clips.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct View {
    /// Degrees around the vertical axis; 0 looks down −z from +z.
    pub azimuth: f32,
    /// Degrees above the horizontal plane.
    pub elevation: f32,
    /// Vertical field of view in degrees.
    pub fov: f32,
    /// Distance from the eye to the near clipping plane, in scene units; `None` fits it to the
    /// scene (just in front of its bounds, or 1/1000 of the eye's distance if that is farther).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub near: Option<f32>,
    /// Distance from the eye to the far clipping plane, in scene units; `None` fits it to the
    /// scene (just behind its bounds).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub far: Option<f32>,
}

impl Default for View {
    fn default() -> Self {
        View { azimuth: 30.0, elevation: 20.0, fov: 45.0, near: None, far: None }
    }
}

/// A fitted camera: view and projection matrices (right-handed, depth in [0, 1]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Camera {
    /// World to view. An orbit camera's view space is scaled by 1/radius of the scene (see the
    /// module docs); `proj` is made for that scale, so only `proj · view` has a meaning of its own.
    pub view: Mat4,
    /// View to clip (`Mat4::perspective_rh`).
    pub proj: Mat4,
    /// The eye position in world space.
    pub eye: Vec3,
    /// The unit viewing direction in world space.
    pub forward: Vec3,
    /// Near plane distance from the eye, in world units.
    pub near: f32,
    /// Far plane distance from the eye, in world units.
    pub far: f32,
}

impl Camera {
    /// The smallest bounding radius an orbit frames. The view·projection matrix scales by 1/r,
    /// times cot(fov/2)/aspect: up to 229 (fov 0.5°) × 16,384 (a 1×16,384 image) ≈ 3.8e6, which
    /// stays a finite f32 (≤ 3.4e38) for r ≥ 1.1e-32; 10⁻³¹ leaves a margin of 9. (Vertices
    /// themselves are placed well enough far below that: a scene of radius r needs steps of about
    /// r·2⁻²⁴, and f32 resolves 2⁻¹⁴⁹ even among subnormal numbers, so down to r ≈ 2⁻¹²⁵.)
    pub const MIN_RADIUS: f64 = 1e-31;

    /// The largest bounding radius an orbit frames: at the narrowest field of view (0.5°) the eye
    /// stands about 241 radii from the centre, and its position must stay a finite f32
    /// (≤ 3.4e38). Every scene within ±[`crate::Mesh::MAX_COORDINATE`] is far inside (a narrow
    /// image moves the eye farther still, up to 3.9e6 radii at 1×16,384; an eye beyond f32 is
    /// refused as too large too).
    pub const MAX_RADIUS: f64 = 1e36;

    /// Orbits around `bounds` at `view`'s angles, framing the bounding sphere, with near/far fitted
    /// to it (or as `view` sets them).
    pub fn orbit(bounds: &Aabb, view: View, aspect: f32) -> Result<Camera, OitError> {
        if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
            return Err(OitError::InvalidScene("scene bounds are empty or not finite".into()));
        }
        let radius = bounds.radius_f64();
        Camera::fit(bounds.center_f64(), radius, radius, view, aspect)
    }

    /// Orbits around `scene`, framing the tightest sphere about its bounds' centre that holds every
    /// vertex (tighter than the box's corners, so the scene fills the frame and depth precision is
    /// not spent on empty space).
    pub fn orbit_scene(scene: &Scene, view: View, aspect: f32) -> Result<Camera, OitError> {
        let bounds = scene.bounds();
        if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
            return Err(OitError::InvalidScene("scene bounds are empty or not finite".into()));
        }
        let center = bounds.center_f64();
        let mut radius2 = 0.0f64;
        for inst in &scene.instances {
            let mesh = scene.instance_parts(inst).1;
            for &p in &mesh.positions {
                let p = inst.transform.transform_point3(p).as_dvec3();
                radius2 = radius2.max(p.distance_squared(center));
            }
        }
        Camera::fit(center, radius2.sqrt(), bounds.radius_f64(), view, aspect)
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
        Camera::fit(center.as_dvec3(), f64::from(radius), f64::from(depth_radius), view, aspect)
    }

    /// [`Camera::orbit_sphere`] in f64: the fit is made in units of the framed radius about
    /// `center`, and the scale goes into the view matrix.
    fn fit(
        center: DVec3,
        radius: f64,
        depth_radius: f64,
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
        for (name, flag, plane) in [("near", "--near", view.near), ("far", "--far", view.far)] {
            if let Some(d) = plane
                && !(d.is_finite() && d > 0.0)
            {
                return Err(OitError::InvalidSettings(format!(
                    "the {name} plane ({flag} {d}) must be a finite distance above 0"
                )));
            }
        }
        let too_large = |radius: f64| {
            OitError::InvalidScene(format!(
                "the scene is too large to frame: its bounding sphere (centre {center}, radius {radius:e}) \
                 puts the camera beyond f32's range; keep coordinates within ±{:e}",
                crate::Mesh::MAX_COORDINATE
            ))
        };
        if !center.is_finite() || !radius.is_finite() || !depth_radius.is_finite() {
            return Err(too_large(radius));
        }
        // f32 vertices far from the origin are coarse: one at distance c is placed to c·2⁻²⁴, so a
        // scene smaller than 1/1000 of its distance from the origin is framed as if it were that
        // large (its vertices' rounding then stays under half a pixel at the largest image size).
        let mut framed = radius.max(1e-3 * center.length());
        if framed == 0.0 {
            // every vertex at the origin: nothing to draw, any frame will do
            framed = 1.0;
        }
        if framed > Camera::MAX_RADIUS {
            return Err(too_large(framed));
        }
        if framed < Camera::MIN_RADIUS {
            return Err(OitError::InvalidScene(format!(
                "the scene is too small to frame: its bounding sphere's radius {framed:e} is below {:e}, \
                 where the camera's view·projection matrix (1/radius) leaves f32's range; scale the model up",
                Camera::MIN_RADIUS
            )));
        }
        // From here on, lengths are in units of `framed`, about `center`.
        let vhalf = f64::from(view.fov).to_radians() * 0.5;
        let half = vhalf.min((vhalf.tan() * f64::from(aspect)).atan());
        let distance = 1.0 / half.sin() * 1.05;
        let (az, el) =
            (f64::from(view.azimuth).to_radians(), f64::from(view.elevation).clamp(-89.0, 89.0).to_radians());
        let dir = DVec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
        let depth = depth_radius.max(framed) / framed;
        let near = match view.near {
            Some(n) => f64::from(n) / framed,
            None => (distance - depth * 1.01).max(distance * 1e-3),
        };
        let far = match view.far {
            Some(f) => f64::from(f) / framed,
            None => distance + depth * 1.01,
        };
        if near >= far {
            let (n, f) = ((near * framed) as f32, (far * framed) as f32);
            return Err(OitError::InvalidSettings(match (view.near, view.far) {
                (Some(_), None) => format!(
                    "the near plane ({n}) lies beyond the far plane fitted to this scene ({f}): \
                     set --far beyond --near, or a smaller --near"
                ),
                (None, Some(_)) => format!(
                    "the far plane ({f}) lies in front of the near plane fitted to this scene ({n}): \
                     set --near below --far, or a larger --far"
                ),
                _ => format!("the near plane ({n}) must be nearer than the far plane ({f})"),
            }));
        }
        let proj = DMat4::perspective_rh(vhalf * 2.0, f64::from(aspect), near, far).as_mat4();
        if !(proj.is_finite() && (near as f32).is_normal() && (proj.w_axis.z != 0.0)) {
            return Err(OitError::InvalidSettings(format!(
                "the near plane ({}) is too close to the eye for f32 at this scene's scale (radius {framed:e}): \
                 use a larger --near",
                (near * framed) as f32
            )));
        }
        let up = if dir.cross(DVec3::Y).length_squared() < 1e-8 { DVec3::Z } else { DVec3::Y };
        let view_matrix = DMat4::look_at_rh(dir * distance, DVec3::ZERO, up)
            * DMat4::from_scale(DVec3::splat(1.0 / framed))
            * DMat4::from_translation(-center);
        let camera = Camera {
            view: view_matrix.as_mat4(),
            proj,
            eye: (center + dir * (distance * framed)).as_vec3(),
            forward: (-dir).as_vec3().normalize(),
            near: (near * framed) as f32,
            far: (far * framed) as f32,
        };
        if !(camera.view_proj().is_finite() && camera.eye.is_finite() && camera.far.is_finite()) {
            return Err(too_large(framed));
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
        // perspective_rh maps z_view = -n to 0 and -f to 1: ndc = f(z + n) / (z (n - f)) with z < 0,
        // so the distance is n·f / (f − d(f − n)), written without the product n·f, which is 0 or
        // infinite in f32 for a scene at 10⁻²⁰ or 10²⁰ (the WGSL resolve has the same formula).
        let (n, f) = (self.near, self.far);
        n / (1.0 - ndc_z * (1.0 - n / f))
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
        // at the narrowest fov the eye stands ~241 radii away: still finite at MAX_COORDINATE
        let m = crate::Mesh::MAX_COORDINATE;
        let big = Aabb { min: Vec3::splat(-m), max: Vec3::splat(m) };
        let c = Camera::orbit(&big, View { fov: 0.5, ..View::default() }, 1.0).unwrap();
        assert!(c.view_proj().is_finite() && c.eye.is_finite());
        // finite boxes whose radius puts the eye beyond f32: "too large", not "not finite"
        for max in [Vec3::new(1e37, 1e37, 0.0), Vec3::new(1e37, 0.0, 0.0), Vec3::splat(f32::MAX)] {
            let huge = Aabb { min: Vec3::ZERO, max };
            let e = Camera::orbit(&huge, View { fov: 0.5, ..View::default() }, 1.0).unwrap_err().to_string();
            assert!(e.contains("too large") && !e.contains("not finite"), "{e}");
        }
    }

    #[test]
    fn smallest_scene_frames_and_smaller_is_named_too_small() {
        // issue 13.6: a radius clamp of 1e-6 framed a scene at 1e-30 as a dot (0 fragments)
        for r in [1e-30f32, 1e-20, 1.0, 1e20, 1e30] {
            let b = Aabb { min: Vec3::splat(-r), max: Vec3::splat(r) };
            let c = Camera::orbit(&b, View::default(), 1.0).unwrap();
            assert!(c.view_proj().is_finite() && c.eye.is_finite() && c.near > 0.0 && c.near < c.far, "{r}");
            // the box's corners land where they land at unit scale
            let unit =
                Camera::orbit(&Aabb { min: -Vec3::ONE, max: Vec3::ONE }, View::default(), 1.0).unwrap();
            for (p, q) in b.corners().iter().zip(Aabb { min: -Vec3::ONE, max: Vec3::ONE }.corners()) {
                let a = c.view_proj().project_point3(*p);
                let e = unit.view_proj().project_point3(q);
                assert!((a - e).abs().max_element() < 1e-5, "{r}: {a} vs {e}");
            }
        }
        let tiny = Aabb { min: Vec3::ZERO, max: Vec3::splat(1e-32) };
        let e = Camera::orbit(&tiny, View::default(), 1.0).unwrap_err().to_string();
        assert!(e.contains("too small") && e.contains("scale the model up"), "{e}");
        // everything at the origin: nothing to draw, but a camera (a zero-fragment frame)
        let point = Aabb { min: Vec3::ZERO, max: Vec3::ZERO };
        assert!(Camera::orbit(&point, View::default(), 1.0).unwrap().view_proj().is_finite());
    }

    #[test]
    fn planes_can_be_set_and_are_checked() {
        let unit = Aabb { min: -Vec3::ONE, max: Vec3::ONE };
        let fitted = Camera::orbit(&unit, View::default(), 1.0).unwrap();
        let set = View { near: Some(0.5), far: Some(20.0), ..View::default() };
        let c = Camera::orbit(&unit, set, 1.0).unwrap();
        assert!((c.near - 0.5).abs() < 1e-6 && (c.far - 20.0).abs() < 1e-5, "{} {}", c.near, c.far);
        assert_eq!(c.eye, fitted.eye, "the planes move, the eye does not");
        // depth 0 at the near plane, 1 at the far plane
        for (d, z) in [(c.near, 0.0), (c.far, 1.0)] {
            let p = c.eye + c.forward * d;
            let ndc = c.view_proj().project_point3(p);
            assert!((ndc.z - z).abs() < 1e-4, "{d}: {}", ndc.z);
            assert!((c.linear_depth(z) - d).abs() <= 1e-5 * d, "{d}: {}", c.linear_depth(z));
        }
        for (near, far, what) in [
            (Some(0.0), None, "--near 0"),
            (Some(-1.0), None, "--near -1"),
            (None, Some(f32::INFINITY), "--far inf"),
            (Some(f32::NAN), None, "--near NaN"),
        ] {
            let e = Camera::orbit(&unit, View { near, far, ..View::default() }, 1.0).unwrap_err().to_string();
            assert!(e.contains(what) && e.contains("above 0"), "{e}");
        }
        // against a fitted plane: the message says which was fitted and where
        let e =
            Camera::orbit(&unit, View { near: Some(1e3), ..View::default() }, 1.0).unwrap_err().to_string();
        assert!(e.contains("far plane fitted") && e.contains("--far"), "{e}");
        let e =
            Camera::orbit(&unit, View { far: Some(1e-3), ..View::default() }, 1.0).unwrap_err().to_string();
        assert!(e.contains("near plane fitted") && e.contains("--near"), "{e}");
        let e = Camera::orbit(&unit, View { near: Some(2.0), far: Some(1.0), ..View::default() }, 1.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("nearer than the far plane"), "{e}");
        // a near plane f32 cannot hold in the camera's units (1e-39 of a unit radius: subnormal)
        let e =
            Camera::orbit(&unit, View { near: Some(1e-39), ..View::default() }, 1.0).unwrap_err().to_string();
        assert!(e.contains("too close to the eye") && e.contains("larger --near"), "{e}");
    }

    #[test]
    fn linear_depth_holds_at_every_scale() {
        // n·f, the old formula's product, is 0 in f32 at 1e-30 and infinite at 1e20
        for r in [1e-30f32, 1.0, 1e20, 1e30] {
            let b = Aabb { min: Vec3::splat(-r), max: Vec3::splat(r) };
            let c = Camera::orbit(&b, View::default(), 1.0).unwrap();
            let mid = c.linear_depth(0.5) / r;
            let unit =
                Camera::orbit(&Aabb { min: -Vec3::ONE, max: Vec3::ONE }, View::default(), 1.0).unwrap();
            assert!((mid - unit.linear_depth(0.5)).abs() < 1e-5, "{r}: {mid}");
        }
    }
}
