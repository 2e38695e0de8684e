//! Every choice of technique the CLI offers, read from the renderer's registry
//! ([`Technique::all`], [`manyshadows::TechniqueInfo`]): `--technique`'s help and default, the
//! benchmarks' default methods, and the checks that refuse a technique where it cannot stand.
//! No other module of the CLI names a technique.

use anyhow::{bail, Result};
use manyshadows::scene::light_space::PointShadows;
use manyshadows::{Fills, RenderError, Technique};

/// The registry's names of the techniques that fill `fills`, in its order.
pub(crate) fn filling(fills: Fills) -> Vec<Technique> {
    Technique::all()
        .into_iter()
        .filter(|t| t.info().fills == fills)
        .collect()
}

/// The first technique that fills `fills` (the default of options that need that kind).
pub(crate) fn first_filling(fills: Fills) -> Technique {
    filling(fills)
        .first()
        .copied()
        .unwrap_or_else(Technique::default)
}

/// Names, comma-separated.
pub(crate) fn names(techniques: &[Technique]) -> String {
    techniques
        .iter()
        .map(|t| t.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// `--technique`'s long help: one paragraph per technique of the registry.
pub(crate) fn help() -> String {
    let mut out = String::from(
        "Shadow technique. All but the last kinds fill the same depth atlas; each line says \
         what a technique fills, the point-light shadows it renders and what it needs:\n",
    );
    for t in Technique::all() {
        let i = t.info();
        let modes: Vec<&str> = i.point_shadows.iter().map(|m| m.name()).collect();
        let needs: Vec<String> = i.needs.iter().map(|n| n.name()).collect();
        out.push_str(&format!(
            "\n  {}{}: {}. Fills {}; point shadows {}{}. ({})",
            t.name(),
            if t == Technique::default() {
                " (default)"
            } else {
                ""
            },
            i.summary,
            i.fills.describe(),
            modes.join(", "),
            if needs.is_empty() {
                String::new()
            } else {
                format!("; needs {}", needs.join(", "))
            },
            i.origin
        ));
    }
    out
}

/// Refuses a technique that fills no atlas where atlas tiles are generated on their own (the
/// shadow-map benchmarks), with the renderer's own words.
pub(crate) fn require_atlas(what: &str, t: Technique) -> Result<()> {
    let fills = t.info().fills;
    if fills != Fills::Atlas {
        bail!(
            "{what}: {} (techniques that fill one: {})",
            RenderError::NoAtlas {
                technique: t,
                fills
            },
            names(&filling(Fills::Atlas))
        );
    }
    Ok(())
}

/// `bench layered`'s default methods: every atlas technique.
pub(crate) fn atlas_names() -> Vec<String> {
    filling(Fills::Atlas)
        .iter()
        .map(|t| t.name().to_string())
        .collect()
}

/// `bench omni`'s default methods: every atlas technique in each point-shadow mode it renders.
pub(crate) fn omni_methods() -> Vec<String> {
    let mut out = Vec::new();
    for mode in PointShadows::ALL {
        for t in filling(Fills::Atlas) {
            if t.info().point_shadows.contains(mode) {
                let m = if *mode == PointShadows::Cube {
                    "cube"
                } else {
                    "dp"
                };
                out.push(format!("{m}:{}", t.name()));
            }
        }
    }
    out
}

/// `bench irregular`'s default methods: the exact techniques (those that fill the mask) and
/// the default technique at 512² and 2048² per view.
pub(crate) fn exact_methods() -> Vec<String> {
    let mut out: Vec<String> = filling(Fills::Mask)
        .iter()
        .map(|t| t.name().to_string())
        .collect();
    for r in [512, 2048] {
        out.push(format!("{}@{r}", Technique::default()));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_registered_technique_is_in_the_help_and_the_defaults_come_from_it() {
        let h = help();
        for t in Technique::all() {
            assert!(
                h.contains(&format!("\n  {}", t.name())),
                "{t} missing from --help"
            );
        }
        assert_eq!(atlas_names().len(), filling(Fills::Atlas).len());
        assert!(omni_methods().iter().any(|m| m.starts_with("dp:")));
        assert!(require_atlas("x", first_filling(Fills::Mask)).is_err());
        assert!(require_atlas("x", Technique::default()).is_ok());
    }
}
