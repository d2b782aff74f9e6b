//! MTL libraries for the OBJ import ([`super::obj`]): parsed here, statement by
//! statement (the module docs of `obj` say what is taken from them).

use std::path::{Path, PathBuf};

use super::text::shown;

/// Name given to an unnamed material (a bare `newmtl`, as Blender 2.61 writes for a
/// material without a name); a bare `usemtl` selects it.
pub(super) const UNNAMED_MATERIAL: &str = "(unnamed)";

/// One MTL material, with what billow takes from it.
#[derive(Clone, Debug)]
pub(super) struct MtlMaterial {
    pub(super) name: String,
    pub(super) kd: Option<[f32; 3]>,
    pub(super) d: Option<f32>,
    pub(super) tr: Option<f32>,
    /// `map_Kd` and `map_d` as written (options and all).
    pub(super) map_kd: Option<String>,
    pub(super) map_d: Option<String>,
    /// The library's folder: texture paths are relative to it.
    pub(super) dir: PathBuf,
}

/// What parsing a library noticed: statements it could not use, and how much it held.
#[derive(Debug, Default)]
pub(super) struct MtlNotes {
    /// Statements ignored because their values do not parse: (line number, text, problem).
    pub(super) bad: Vec<(usize, String, String)>,
    /// Non-blank lines that are not comments.
    pub(super) statements: usize,
    pub(super) materials: usize,
    /// Statements whose keyword is not MTL, and the first of them.
    pub(super) unknown: usize,
    pub(super) first_unknown: Option<(usize, String)>,
    pub(super) first_statement: Option<(usize, String)>,
}

impl MtlNotes {
    /// The warnings about library `p`: its first bad statement (and how many more), and a
    /// library that holds statements but no material.
    pub(super) fn warnings(&self, p: &Path) -> Vec<String> {
        let mut out = Vec::new();
        if let Some((line, text, problem)) = self.bad.first() {
            let more = match self.bad.len() - 1 {
                0 => String::new(),
                1 => " (and 1 more such statement)".into(),
                n => format!(" (and {n} more such statements)"),
            };
            out.push(format!(
                "material library {}: line {line}: '{}': {problem}; the statement is ignored{more}",
                p.display(),
                shown(text)
            ));
        }
        // A library with statements but no material (an empty one says nothing).
        let described = match (&self.first_unknown, &self.first_statement) {
            (Some(u), _) => Some((
                format!(
                    "{} of its {} statements are not MTL",
                    self.unknown, self.statements
                ),
                u,
            )),
            (None, Some(s)) => Some((
                format!("none of its {} statements is `newmtl`", self.statements),
                s,
            )),
            (None, None) => None,
        };
        if let (0, Some((what, (line, text)))) = (self.materials, described) {
            out.push(format!(
                "material library {} defines no material: {what} (the first, line {line}: '{}')",
                p.display(),
                shown(text)
            ));
        }
        out
    }
}

/// Statement keywords of the MTL format (lower case; matched without regard to case) that
/// billow reads or knowingly ignores.
pub(super) const MTL_KEYWORDS: &[&str] = &[
    "newmtl",
    "ka",
    "kd",
    "ks",
    "ke",
    "tf",
    "d",
    "tr",
    "ns",
    "ni",
    "illum",
    "sharpness",
    "map_ka",
    "map_kd",
    "map_ks",
    "map_ke",
    "map_ns",
    "map_d",
    "map_tr",
    "map_bump",
    "bump",
    "disp",
    "decal",
    "refl",
    "map_refl",
    "map_aat",
    "pr",
    "pm",
    "ps",
    "pc",
    "pcr",
    "aniso",
    "anisor",
    "norm",
    "map_pr",
    "map_pm",
    "map_ps",
    "map_norm",
];

/// Parses an MTL library, statement by statement: a statement whose values do not parse
/// is noted ([`MtlNotes::bad`]) and ignored, never the whole library. Colours (`Ka`, `Kd`,
/// `Ks`, `Ke`, `Tf`) take one value (grey: g = b = r), three, or `xyz` and CIE XYZ values;
/// `d` takes `-halo`; a bare `newmtl` names [`UNNAMED_MATERIAL`]; a texture statement
/// without a file name says nothing. Statements before the first `newmtl` are ignored.
pub(super) fn parse_mtl(text: &str, dir: &Path) -> (Vec<MtlMaterial>, MtlNotes) {
    let mut materials: Vec<MtlMaterial> = Vec::new();
    let mut notes = MtlNotes::default();
    for (n, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        notes.statements += 1;
        notes.first_statement.get_or_insert((n + 1, t.to_string()));
        let (keyword, rest) = t.split_once(char::is_whitespace).unwrap_or((t, ""));
        let rest = rest.trim();
        let keyword = keyword.to_ascii_lowercase();
        if keyword == "newmtl" {
            materials.push(MtlMaterial {
                name: if rest.is_empty() {
                    UNNAMED_MATERIAL.to_string()
                } else {
                    rest.to_string()
                },
                kd: None,
                d: None,
                tr: None,
                map_kd: None,
                map_d: None,
                dir: dir.to_path_buf(),
            });
            continue;
        }
        if !MTL_KEYWORDS.contains(&keyword.as_str()) {
            notes.unknown += 1;
            notes.first_unknown.get_or_insert((n + 1, t.to_string()));
            continue;
        }
        let Some(m) = materials.last_mut() else {
            continue;
        };
        let file = || (!rest.is_empty()).then(|| rest.to_string());
        let r: Result<(), String> = match keyword.as_str() {
            "ka" | "ks" | "ke" | "tf" => mtl_colour(rest).map(drop),
            "kd" => mtl_colour(rest).map(|c| m.kd = Some(c)),
            "d" => {
                let v = rest.strip_prefix("-halo").map_or(rest, str::trim_start);
                mtl_number(v).map(|v| m.d = Some(v))
            }
            "tr" => mtl_number(rest).map(|v| m.tr = Some(v)),
            "map_kd" => {
                m.map_kd = file().or(m.map_kd.take());
                Ok(())
            }
            "map_d" => {
                m.map_d = file().or(m.map_d.take());
                Ok(())
            }
            _ => Ok(()),
        };
        if let Err(problem) = r {
            notes.bad.push((n + 1, t.to_string(), problem));
        }
    }
    notes.materials = materials.len();
    (materials, notes)
}

/// One number, the first word of `s`.
pub(super) fn mtl_number(s: &str) -> Result<f32, String> {
    let w = s.split_whitespace().next().ok_or("a number is missing")?;
    w.parse::<f32>()
        .map_err(|_| format!("'{w}' is not a number"))
}

/// An MTL colour: `r [g b]` (one value is grey), or `xyz x [y z]` (CIE XYZ, turned into
/// linear sRGB); `spectral` curves are not supported.
pub(super) fn mtl_colour(s: &str) -> Result<[f32; 3], String> {
    let mut words = s.split_whitespace().peekable();
    let xyz = match words.peek() {
        Some(&"spectral") => return Err("spectral colours (.rfl files) are not supported".into()),
        Some(&"xyz") => {
            words.next();
            true
        }
        _ => false,
    };
    let values = words
        .map(|w| {
            w.parse::<f32>()
                .map_err(|_| format!("'{w}' is not a number"))
        })
        .collect::<Result<Vec<f32>, String>>()?;
    let c = match values[..] {
        [v] => [v; 3],
        [r, g, b, ..] => [r, g, b],
        _ => {
            return Err(format!(
                "a colour is one value (grey) or three (r g b), not {}",
                values.len()
            ))
        }
    };
    Ok(if xyz {
        let [x, y, z] = c;
        [
            3.240_454_2 * x - 1.537_138_5 * y - 0.498_531_4 * z,
            -0.969_266 * x + 1.876_010_8 * y + 0.041_556 * z,
            0.055_643_4 * x - 0.204_025_9 * y + 1.057_225_2 * z,
        ]
    } else {
        c
    })
}
