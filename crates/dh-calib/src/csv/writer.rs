//! Writing [`Measurements`] as the canonical CSV ([`write_measurements`]): metres, radians,
//! shortest round-tripping numbers, names quoted when they need it.

use super::*;

/// Writes a measurement set in the canonical CSV layout: metres, radians, points in the device
/// frame, numbers in Rust's shortest round-trip form, so that [`parse_measurements`] with the
/// same joint names and default options gives back the same set (except `Sample::line`, which
/// becomes the line in the written text).
///
/// Columns: the joints, `x,y,z`, `target`; `config` when any sample has one; `sigma` when every
/// known standard deviation is isotropic, else `sx,sy,sz`; `set` when any sample is for
/// validation; `socket` when any sample is a contact, with `partner,distance,distance_sigma`
/// when any socket has a partner (contact rows leave `x,y,z` empty); `session` when the set
/// names sessions; `qw,qx,qy,qz,sigma_rot` when any sample has an orientation (point rows
/// leave them empty); `time` (seconds) when any sample has one. Targets are written by name, so a target that no sample uses is not kept, and the
/// targets come back numbered in order of first use.
pub fn write_measurements(m: &Measurements) -> String {
    let any_config = m.samples.iter().any(|s| s.config.is_some());
    let sigmas: Vec<&Vector3<f64>> = m.samples.iter().filter_map(|s| s.sigma.as_ref()).collect();
    let any_sigma = !sigmas.is_empty();
    let isotropic = sigmas.iter().all(|s| s.x == s.y && s.y == s.z);
    let any_validation = m.samples.iter().any(|s| s.split == Split::Validation);
    let any_socket = m.samples.iter().any(|s| s.socket.is_some());
    let any_partner = m
        .samples
        .iter()
        .any(|s| s.socket.as_ref().is_some_and(|c| c.partner.is_some()));

    let mut out = String::from(
        "# urdf-dh measurements: joints in rad (m for prismatic), x,y,z in m in the device frame\n",
    );
    let mut header: Vec<String> = m.joint_names.iter().map(|n| quote(n)).collect();
    header.extend(["x", "y", "z", "target"].map(String::from));
    if any_config {
        header.push("config".into());
    }
    if any_sigma {
        if isotropic {
            header.push("sigma".into());
        } else {
            header.extend(["sx", "sy", "sz"].map(String::from));
        }
    }
    if any_validation {
        header.push("set".into());
    }
    if any_socket {
        header.push("socket".into());
    }
    if any_partner {
        header.extend(["partner", "distance", "distance_sigma"].map(String::from));
    }
    let any_session = !m.sessions.is_empty();
    if any_session {
        header.push("session".into());
    }
    let any_orientation = m.samples.iter().any(|s| s.orientation.is_some());
    if any_orientation {
        header.extend(QUATERNION_COLUMNS.map(String::from));
        header.push("sigma_rot".into());
    }
    let any_time = m.samples.iter().any(|s| s.time.is_some());
    if any_time {
        header.push("time".into());
    }
    out.push_str(&header.join(","));
    out.push('\n');

    for s in &m.samples {
        let mut cells: Vec<String> = s.q.iter().map(|v| format!("{v:?}")).collect();
        match s.socket {
            Some(_) => cells.extend([String::new(), String::new(), String::new()]),
            None => cells.extend(s.point.iter().map(|v| format!("{v:?}"))),
        }
        let target = m
            .targets
            .get(s.target)
            .map_or(DEFAULT_TARGET, String::as_str);
        cells.push(quote(target));
        if any_config {
            cells.push(s.config.as_deref().map(quote).unwrap_or_default());
        }
        if any_sigma {
            match (&s.sigma, isotropic) {
                (Some(v), true) => cells.push(format!("{:?}", v.x)),
                (Some(v), false) => cells.extend(v.iter().map(|c| format!("{c:?}"))),
                (None, true) => cells.push(String::new()),
                (None, false) => cells.extend([String::new(), String::new(), String::new()]),
            }
        }
        if any_validation {
            cells.push(
                match s.split {
                    Split::Calibration => "calibration",
                    Split::Validation => "validation",
                }
                .into(),
            );
        }
        if any_socket {
            cells.push(
                s.socket
                    .as_ref()
                    .map(|c| quote(&c.name))
                    .unwrap_or_default(),
            );
        }
        if any_partner {
            match s.socket.as_ref().and_then(|c| c.partner.as_ref()) {
                Some(p) => cells.extend([
                    quote(&p.socket),
                    format!("{:?}", p.distance),
                    format!("{:?}", p.sigma),
                ]),
                None => cells.extend([String::new(), String::new(), String::new()]),
            }
        }
        if any_session {
            cells.push(quote(&m.session_name(s.session)));
        }
        if any_orientation {
            match &s.orientation {
                Some(o) => {
                    let q = o.rotation.quaternion();
                    cells.extend([q.w, q.i, q.j, q.k, o.sigma].map(|v| format!("{v:?}")));
                }
                None => cells.extend((0..5).map(|_| String::new())),
            }
        }
        if any_time {
            cells.push(s.time.map(|t| format!("{t:?}")).unwrap_or_default());
        }
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out
}

/// Quotes a cell when it holds a delimiter, a quote, a line break, surrounding spaces, a
/// leading `#` or nothing at all would be mistaken for something else.
pub(super) fn quote(s: &str) -> String {
    let needs =
        s.contains([',', '"', '\n', '\r']) || s.trim() != s || s.starts_with('#') || s.is_empty();
    if needs {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
