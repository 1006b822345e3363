//! Reading the sets and the fixture models (a deliberately small reader of the sheet format).

use super::*;

pub(crate) const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

pub(crate) fn shared(set: &str) -> PathBuf {
    Path::new(ROOT).join("../shared/measured").join(set)
}

pub(crate) fn fixture(set: &str, file: &str) -> PathBuf {
    Path::new(ROOT)
        .join("fixtures/measured")
        .join(set)
        .join(file)
}

pub(crate) type Error = Box<dyn std::error::Error>;

/// One set's run.
pub(crate) type Run = fn() -> Result<(), Error>;

pub(crate) fn read(path: &Path) -> Result<String, Error> {
    std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()).into())
}

pub(crate) fn load(layout: Layout, dir: &Path, files: &[&str]) -> Result<Measurements, Error> {
    let mut texts = Vec::new();
    for f in files {
        texts.push((*f, read(&dir.join(f))?));
    }
    let sources: Vec<Source<'_>> = texts
        .iter()
        .map(|(name, text)| Source { name, text })
        .collect();
    Ok(import(layout, &sources)?)
}

// ---------------------------------------------------------------- fixture readers

pub(crate) fn num(v: &Value) -> Result<f64, Error> {
    v.as_f64()
        .or_else(|| v.as_i64().map(|i| i as f64))
        .ok_or_else(|| format!("expected a number, found {v:?}").into())
}

pub(crate) fn vec3(v: &Value) -> Result<Vector3<f64>, Error> {
    let s = v.as_sequence().ok_or("expected [x, y, z]")?;
    if s.len() != 3 {
        return Err("expected three numbers".into());
    }
    Ok(Vector3::new(num(&s[0])?, num(&s[1])?, num(&s[2])?))
}

pub(crate) struct Units {
    pub(crate) length: f64,
    pub(crate) angle: f64,
}

pub(crate) fn units(doc: &Value) -> Units {
    Units {
        length: if doc["length_unit"].as_str() == Some("mm") {
            1e-3
        } else {
            1.0
        },
        angle: if doc["angle_unit"].as_str() == Some("deg") {
            std::f64::consts::PI / 180.0
        } else {
            1.0
        },
    }
}

pub(crate) fn pose(v: &Value, u: &Units) -> Result<Isometry3<f64>, Error> {
    if v.is_null() {
        return Ok(Isometry3::identity());
    }
    let t = vec3(&v["xyz"])? * u.length;
    let r = vec3(&v["rpy"])? * u.angle;
    Ok(from_xyz_rpy([t.x, t.y, t.z], [r.x, r.y, r.z]))
}

pub(crate) fn table(doc: &Value, convention: Convention, u: &Units) -> Result<DhTable, Error> {
    let mut rows = Vec::new();
    for j in doc["joints"].as_sequence().ok_or("expected 'joints'")? {
        let name = j["name"].as_str().ok_or("joint without a name")?;
        let (a, alpha, d, theta) = (
            num(&j["a"])? * u.length,
            num(&j["alpha"])? * u.angle,
            num(&j["d"])? * u.length,
            num(&j["theta"])? * u.angle,
        );
        let mut row = if j["type"].as_str() == Some("prismatic") {
            DhRow::prismatic(name, a, alpha, d, theta)
        } else {
            DhRow::revolute(name, a, alpha, d, theta)
        };
        if !j["lower"].is_null() {
            let s = if row.kind == JointKind::Prismatic {
                u.length
            } else {
                u.angle
            };
            row.limits = Some(Limits {
                lower: num(&j["lower"])? * s,
                upper: num(&j["upper"])? * s,
            });
        }
        rows.push(row);
    }
    Ok(DhTable {
        convention,
        base: pose(&doc["base"], u)?,
        tool: pose(&doc["tool"], u)?,
        rows,
    })
}

pub(crate) fn convention(doc: &Value) -> Convention {
    if doc["convention"].as_str() == Some("modified") {
        Convention::Modified
    } else {
        Convention::Standard
    }
}

/// A serial DH sheet, with its coupled joints and the inertials of `inertials.yaml` beside it.
pub(crate) struct Robot {
    pub(crate) tree: DhTree,
    pub(crate) coupled: Vec<(String, Vec<(String, f64)>)>,
    pub(crate) inertials: Option<Inertials>,
    pub(crate) gravity: Vector3<f64>,
}

pub(crate) fn read_inertials(
    doc: &Value,
    tree: &DhTree,
) -> Result<(Inertials, Vector3<f64>), Error> {
    let gravity = if doc["gravity"].is_null() {
        GravityModel::default_gravity()
    } else {
        vec3(&doc["gravity"])?
    };
    let mut links = Vec::new();
    for l in doc["links"].as_sequence().ok_or("expected 'links'")? {
        let name = l["joint"]
            .as_str()
            .ok_or("link without a joint")?
            .to_string();
        links.push((name, num(&l["mass"])?, vec3(&l["com"])?));
    }
    let mut payloads = Vec::new();
    if let Some(ps) = doc["payloads"].as_sequence() {
        for p in ps {
            payloads.push((
                0,
                Inertial {
                    mass: num(&p["mass"])?,
                    com: vec3(&p["com"])?,
                },
            ));
        }
    }
    let inertials = if doc["com_frame"].as_str() == Some("dh") {
        Inertials {
            links: links
                .into_iter()
                .map(|(n, mass, com)| (n, Inertial { mass, com }))
                .collect(),
            payloads,
        }
    } else {
        Inertials::from_zero_pose(tree, &links, payloads)?
    };
    Ok((inertials, gravity))
}

pub(crate) fn read_robot(set: &str) -> Result<Robot, Error> {
    let doc: Value = serde_yaml::from_str(&read(&fixture(set, "model.yaml"))?)?;
    let u = units(&doc);
    let conv = convention(&doc);
    let trunk = table(&doc, conv, &u)?;
    if !doc["branches"].is_null() {
        return Err(format!("{set}: a tree sheet; trees run through urdf-dh calibrate").into());
    }
    let tree = DhTree::serial(&trunk);
    let mut coupled = Vec::new();
    if let Some(map) = doc["coupled"].as_mapping() {
        for (k, v) in map {
            let terms = v
                .as_mapping()
                .ok_or("expected driver: coefficient pairs")?
                .iter()
                .map(|(d, c)| Ok((d.as_str().ok_or("bad driver")?.to_string(), num(c)?)))
                .collect::<Result<Vec<_>, Error>>()?;
            coupled.push((k.as_str().ok_or("bad coupled joint")?.to_string(), terms));
        }
    }
    let path = fixture(set, "inertials.yaml");
    let inertial_doc = if path.exists() {
        Some(serde_yaml::from_str::<Value>(&read(&path)?)?)
    } else {
        None
    };
    let (inertials, gravity) = match inertial_doc {
        Some(d) => {
            let (i, g) = read_inertials(&d, &tree)?;
            (Some(i), g)
        }
        None => (None, GravityModel::default_gravity()),
    };
    Ok(Robot {
        tree,
        coupled,
        inertials,
        gravity,
    })
}

/// Adds (or replaces) the coupled joints' columns: value = Σ coefficient × driver.
pub(crate) fn apply_coupling(
    m: &mut Measurements,
    coupled: &[(String, Vec<(String, f64)>)],
) -> Result<(), Error> {
    for (joint, terms) in coupled {
        let idx: Vec<(usize, f64)> = terms
            .iter()
            .map(|(d, c)| {
                m.joint_names
                    .iter()
                    .position(|n| n == d)
                    .map(|i| (i, *c))
                    .ok_or_else(|| format!("coupled joint {joint}: no column {d}"))
            })
            .collect::<Result<_, _>>()?;
        let at = m.joint_names.iter().position(|n| n == joint);
        let col = match at {
            Some(i) => i,
            None => {
                m.joint_names.push(joint.clone());
                for s in &mut m.samples {
                    s.q = s.q.iter().copied().chain([0.0]).collect();
                }
                m.joint_names.len() - 1
            }
        };
        for s in &mut m.samples {
            // A term on the joint itself keeps its own value (FANUC J2/J3: J3 + J2).
            let mut q = s.q.to_vec();
            q[col] = idx.iter().map(|(i, c)| c * s.q[*i]).sum();
            s.q = q.into();
        }
    }
    Ok(())
}

// ---------------------------------------------------------------- reports
