//! Is this the scene a store was baked from? The scene against a store's scene section.
//!
//! Input: what a store recorded of its scene (`SceneSection`: object count, fingerprint, CRS;
//! `docs/FORMAT.md` section 5.2) and the same facts of a loaded scene ([`SceneFacts`]).
//! Output: [`SceneCheck`]: the same scene, nothing recorded to check against (every 1.0 store),
//! or what differs ([`SceneMismatch`], whose message names the fields that differ and the likely
//! cause: other reader flags, another CRS, or another file or version of it).
//! Invariants: a field the store did not record (0, or an empty CRS) is never compared; a
//! scene is "the same" only when every recorded field is equal; the likely cause is a guess
//! from the counts, worded as one, and decides nothing.

use std::fmt;

use super::Scene;
use crate::runtime::format::SceneSection;

/// The bytes a store keeps of a CRS name: at most 255, cut at a character boundary (as the
/// bake writes it).
fn stored_crs(name: &str) -> &str {
    let mut end = name.len().min(255);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    &name[..end]
}

/// What the check needs of a loaded scene: what a store records of it, and how many of the
/// files' features the readers skipped (to tell other reader flags from another file).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneFacts {
    /// Objects loaded.
    pub objects: u64,
    /// [`Scene::fingerprint`].
    pub fingerprint: u64,
    /// The scene's CRS name (`EPSG:3946`); empty when unknown.
    pub crs: String,
    /// Features the readers skipped (no height, a bad ring, ...).
    pub skipped: u64,
}

impl SceneFacts {
    pub fn of(scene: &Scene) -> SceneFacts {
        SceneFacts {
            objects: scene.objects.len() as u64,
            fingerprint: scene.fingerprint(),
            crs: scene.crs().map(|c| c.name.clone()).unwrap_or_default(),
            skipped: scene.report.skipped.len() as u64,
        }
    }
}

/// The likely reason a scene differs from the one baked (a guess from the counts).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LikelyCause {
    /// The CRS differs: another `--crs`, or files in another CRS.
    Crs,
    /// Fewer objects, but the files hold as many features as were baked: some were skipped
    /// here that the bake read (other reader flags: `--height-attr`, `--default-height`, ...).
    SkippedHere,
    /// More objects than were baked: the bake skipped features this load reads (other reader
    /// flags), or another file.
    MoreObjects,
    /// Fewer features in the files than objects baked: another file, or another version of it.
    FewerFeatures,
    /// The same object count, other boxes: reader flags that change heights or bases, or
    /// another version of the file.
    SameCount,
}

/// What differs between a scene and the one a store was baked from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneMismatch {
    /// The store's scene section (0 and "" where not recorded).
    pub baked_objects: u64,
    pub baked_fingerprint: u64,
    pub baked_crs: String,
    /// The scene given.
    pub scene: SceneFacts,
    pub cause: LikelyCause,
}

/// The result of [`check`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SceneCheck {
    /// Every recorded field is equal.
    Same,
    /// The store records no scene (a 1.0 store): the check could not be made.
    NotRecorded,
    Differs(Box<SceneMismatch>),
}

/// Checks `scene` against the scene section a store recorded.
pub fn check(baked: &SceneSection<'_>, scene: &SceneFacts) -> SceneCheck {
    if baked.objects == 0 && baked.scene == 0 && baked.crs.is_empty() {
        return SceneCheck::NotRecorded;
    }
    let objects_differ = baked.objects != 0 && u64::from(baked.objects) != scene.objects;
    let fingerprint_differs = baked.scene != 0 && baked.scene != scene.fingerprint;
    let crs_differs = !baked.crs.is_empty() && baked.crs != stored_crs(&scene.crs);
    if !objects_differ && !fingerprint_differs && !crs_differs {
        return SceneCheck::Same;
    }
    let baked_objects = u64::from(baked.objects);
    let cause = if crs_differs {
        LikelyCause::Crs
    } else if !objects_differ {
        LikelyCause::SameCount
    } else if scene.objects > baked_objects {
        LikelyCause::MoreObjects
    } else if scene.objects + scene.skipped >= baked_objects {
        LikelyCause::SkippedHere
    } else {
        LikelyCause::FewerFeatures
    };
    SceneCheck::Differs(Box::new(SceneMismatch {
        baked_objects,
        baked_fingerprint: baked.scene,
        baked_crs: baked.crs.to_string(),
        scene: scene.clone(),
        cause,
    }))
}

impl SceneMismatch {
    /// The fields that differ, as "2571 objects where 2576 were baked, ...".
    pub fn differences(&self) -> String {
        let s = &self.scene;
        let mut d = Vec::new();
        if self.baked_objects != 0 && self.baked_objects != s.objects {
            d.push(format!(
                "{} objects where {} were baked",
                s.objects, self.baked_objects
            ));
        }
        if self.baked_fingerprint != 0 && self.baked_fingerprint != s.fingerprint {
            d.push(format!(
                "fingerprint {:016x} where {:016x} was baked",
                s.fingerprint, self.baked_fingerprint
            ));
        }
        if !self.baked_crs.is_empty() && self.baked_crs != stored_crs(&s.crs) {
            let now = if s.crs.is_empty() { "unknown" } else { &s.crs };
            d.push(format!("CRS {now} where {} was baked", self.baked_crs));
        }
        d.join(", ")
    }

    /// The likely cause, in words.
    pub fn likely_cause(&self) -> String {
        let s = &self.scene;
        match self.cause {
            LikelyCause::Crs => {
                "another CRS (another --crs, or files in another coordinate system)".to_string()
            }
            LikelyCause::SkippedHere => format!(
                "other reader flags: {} features were skipped here (`vocc info` lists them and why), which the bake read",
                s.skipped
            ),
            LikelyCause::MoreObjects => {
                "other reader flags (the bake skipped features this load reads: --default-height, --levels-attr, ...) or another file".to_string()
            }
            LikelyCause::FewerFeatures => {
                "another file, or another version of it (the files hold fewer features than objects were baked)".to_string()
            }
            LikelyCause::SameCount => {
                "other reader flags that change heights or bases (--height-attr, --base-attr, --levels-attr, --storey-height, --lod, ...), or another version of the file".to_string()
            }
        }
    }
}

impl fmt::Display for SceneMismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the scene is not the one the store was baked from: {}; likely {}",
            self.differences(),
            self.likely_cause()
        )
    }
}

impl std::error::Error for SceneMismatch {}

#[cfg(test)]
mod tests {
    use super::*;

    fn facts(objects: u64, fingerprint: u64, crs: &str, skipped: u64) -> SceneFacts {
        SceneFacts {
            objects,
            fingerprint,
            crs: crs.into(),
            skipped,
        }
    }

    fn section(objects: u32, scene: u64, crs: &str) -> SceneSection<'_> {
        SceneSection {
            objects,
            scene,
            crs,
        }
    }

    #[test]
    fn equal_recorded_fields_are_the_same_scene_and_unrecorded_ones_are_not_compared() {
        let s = facts(10, 7, "EPSG:3946", 0);
        assert_eq!(check(&section(10, 7, "EPSG:3946"), &s), SceneCheck::Same);
        // A 2.0 store baked before the CRS was recorded.
        assert_eq!(check(&section(10, 7, ""), &s), SceneCheck::Same);
        assert_eq!(check(&SceneSection::NONE, &s), SceneCheck::NotRecorded);
    }

    #[test]
    fn the_likely_cause_follows_the_counts() {
        let cause = |baked: SceneSection<'_>, s: SceneFacts| match check(&baked, &s) {
            SceneCheck::Differs(m) => m.cause,
            other => panic!("{other:?}"),
        };
        let b = section(10, 7, "EPSG:3946");
        assert_eq!(cause(b, facts(10, 7, "EPSG:32631", 0)), LikelyCause::Crs);
        assert_eq!(
            cause(b, facts(8, 9, "EPSG:3946", 2)),
            LikelyCause::SkippedHere
        );
        assert_eq!(
            cause(b, facts(12, 9, "EPSG:3946", 0)),
            LikelyCause::MoreObjects
        );
        assert_eq!(
            cause(b, facts(8, 9, "EPSG:3946", 0)),
            LikelyCause::FewerFeatures
        );
        assert_eq!(
            cause(b, facts(10, 9, "EPSG:3946", 0)),
            LikelyCause::SameCount
        );
    }

    #[test]
    fn the_message_names_what_differs_and_the_likely_cause() {
        let SceneCheck::Differs(m) = check(
            &section(2576, 0x5c9c_2944_7b26_bdad, "EPSG:3946"),
            &facts(2571, 0x1234, "EPSG:3946", 5),
        ) else {
            panic!()
        };
        let msg = m.to_string();
        assert!(msg.contains("2571 objects where 2576 were baked"), "{msg}");
        assert!(
            msg.contains("fingerprint 0000000000001234 where 5c9c29447b26bdad was baked"),
            "{msg}"
        );
        assert!(msg.contains("5 features were skipped here"), "{msg}");
        assert!(!msg.contains("CRS"), "{msg}");
    }
}
