//! A private `XDG_RUNTIME_DIR` for a process started without one, so the Vulkan driver stack's
//! `error: XDG_RUNTIME_DIR is invalid or not set in the environment.` never reaches the user.
//!
//! Where the line comes from: Mesa's implicit device-select layer (`VK_LAYER_MESA_device_select`,
//! installed with `mesa-vulkan-drivers`), on every `vkEnumeratePhysicalDevices` of an instance
//! that enabled `VK_KHR_wayland_surface` (wgpu enables every surface extension the loader offers),
//! asks the Wayland compositor which GPU is the primary one: `wl_display_connect(NULL)`, which
//! prints that line from libwayland-client when `XDG_RUNTIME_DIR` is unset or not absolute. It is
//! printed once or twice per command that opens a GPU backend (`oit info`, `--backend all`, ...),
//! and reads as oit's own error.
//!
//! What pre-empts it: only the environment, read by C code when the driver loads
//! (`XDG_RUNTIME_DIR`, `WAYLAND_DISPLAY` as an absolute path, `NODEVICE_SELECT`,
//! `MESA_VK_DEVICE_SELECT`); no wgpu or Vulkan setting reaches the layer. The process's own
//! environment can only be changed with `std::env::set_var`, which is `unsafe` in edition 2024,
//! and the workspace *forbids* `unsafe_code` (a level no `#[allow]` may lower). Filtering stderr
//! needs `dup2`, unsafe as well. So the honest safe option is the one taken here: when
//! `XDG_RUNTIME_DIR` is unset (or not an absolute path), `oit` creates a fresh private directory
//! (mode 0700, under [`std::env::temp_dir`]), runs itself again with the same arguments and
//! `XDG_RUNTIME_DIR` pointing there, waits, removes the directory and exits with the child's
//! status. The child finds the variable set and runs the command itself. The layer's connect then
//! finds no compositor socket in the empty directory and fails without a word, as it does on any
//! machine with a runtime directory and no Wayland.
//!
//! The cost: one more process start (a few milliseconds) for a run without a runtime directory
//! (a container, a CI job, `ssh` without a login session). Terminal signals reach both processes
//! (they share the process group); a signal sent to the parent's pid alone leaves the child to
//! finish its command. Where the directory cannot be made or the binary cannot be started again,
//! the command runs in this process as before, the line and all.

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::ExitCode;

/// Whether `value` (of `XDG_RUNTIME_DIR`) is one libwayland accepts: set and absolute.
fn usable(value: Option<OsString>) -> bool {
    value.is_some_and(|d| PathBuf::from(d).is_absolute())
}

/// A new directory only this user can enter; `None` when one cannot be made.
fn private_dir() -> Option<PathBuf> {
    use std::os::unix::fs::DirBuilderExt;
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).ok()?.subsec_nanos();
    let base = std::env::temp_dir();
    (0..8u32).find_map(|attempt| {
        let dir = base.join(format!("oit-runtime-{}-{nanos:08x}-{attempt}", std::process::id()));
        // `create` refuses a path that exists (a file, a directory or a link someone put there),
        // so the directory is this process's own
        std::fs::DirBuilder::new().mode(0o700).create(&dir).ok().map(|()| dir)
    })
}

/// When `XDG_RUNTIME_DIR` is missing, runs this `oit` again with a private one and returns its
/// exit status; `None` when the variable is set (or the fallback applies): run the command here.
pub fn rerun_with_private_runtime_dir() -> Option<ExitCode> {
    use std::os::unix::process::{CommandExt, ExitStatusExt};
    if usable(std::env::var_os("XDG_RUNTIME_DIR")) {
        return None;
    }
    let exe = std::env::current_exe().ok()?;
    let mut args = std::env::args_os();
    let arg0 = args.next().unwrap_or_else(|| "oit".into());
    let dir = private_dir()?;
    let status = std::process::Command::new(&exe).arg0(arg0).args(args).env("XDG_RUNTIME_DIR", &dir).status();
    // empty unless something made a socket in it; ours to remove either way
    let _ = std::fs::remove_dir_all(&dir);
    let status = status.ok()?;
    Some(match (status.code(), status.signal()) {
        (Some(code), _) => ExitCode::from(u8::try_from(code).unwrap_or(1)),
        // as a shell reports a child killed by a signal
        (None, Some(signal)) => ExitCode::from(u8::try_from(128 + signal).unwrap_or(1)),
        (None, None) => ExitCode::FAILURE,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unset, empty and relative values are the ones libwayland complains about.
    /// Fails if `usable` accepts a relative path (`run` would then skip the private directory
    /// where the line still appears).
    #[test]
    fn only_absolute_runtime_dirs_are_usable() {
        assert!(!usable(None));
        assert!(!usable(Some("".into())));
        assert!(!usable(Some("run/user/1000".into())));
        assert!(usable(Some("/run/user/1000".into())));
    }

    /// The directory is new, a directory, and private (0700).
    /// Fails if the mode is dropped from the `DirBuilder` (0755 under the usual umask).
    #[test]
    fn private_dir_is_fresh_and_private() {
        use std::os::unix::fs::PermissionsExt;
        let (a, b) = (private_dir().unwrap(), private_dir().unwrap());
        assert_ne!(a, b);
        for dir in [&a, &b] {
            let meta = std::fs::symlink_metadata(dir).unwrap();
            assert!(meta.is_dir());
            assert_eq!(meta.permissions().mode() & 0o777, 0o700, "{}", dir.display());
            std::fs::remove_dir(dir).unwrap();
        }
    }
}
