//! `manyshadows bench suite`: the headline measurements in one command, for a GPU — seed 000's
//! layered-against-traditional sweep, the point-light (omni) comparison, and every kind of
//! shadow from 16 to 16,384 lights at 1080p — each run as its own `bench` subcommand (a child
//! process with its own device, its own progress bar and its own output directory), then one
//! table (`suite.txt`: the sections' tables in order, each naming its adapter) and one
//! `suite.json` (the sections' arguments and results).

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};
use clap::Args;

/// Arguments of `manyshadows bench suite`.
#[derive(Args, Debug, Clone)]
pub struct SuiteArgs {
    /// Directory for suite.txt, suite.json and one subdirectory per section.
    #[arg(long, default_value = "bench-suite")]
    pub out_dir: PathBuf,
    /// Tiny sizes, one repeat: checks that every section runs (minutes on a CPU adapter), not a
    /// measurement.
    #[arg(long)]
    pub quick: bool,
    /// Graphics backend for every section (vulkan, gl, metal, dx12; default: WGPU_BACKEND, else
    /// the best adapter).
    #[arg(long)]
    pub backend: Option<String>,
    /// Adapter for every section: the one whose name contains this text.
    #[arg(long)]
    pub adapter: Option<String>,
}

/// One section: a bench subcommand and its arguments (full, then `--quick`).
struct Section {
    name: &'static str,
    what: &'static str,
    full: &'static [&'static str],
    quick: &'static [&'static str],
}

const SECTIONS: &[Section] = &[
    Section {
        name: "layered",
        what: "seed 000: one pass per map against one pass for all, 1 to 32 maps, every variant",
        full: &["layered"],
        quick: &[
            "layered",
            "--maps",
            "1,4",
            "--resolutions",
            "128",
            "--variants",
            "simple",
            "--repeats",
            "1",
            "--warmup",
            "0",
        ],
    },
    Section {
        name: "omni",
        what: "seed 003: cube maps against dual paraboloids for 1 to 16 point lights",
        full: &["omni"],
        quick: &[
            "omni",
            "--lights",
            "1,2",
            "--resolution",
            "64",
            "--repeats",
            "1",
            "--warmup",
            "0",
        ],
    },
    Section {
        name: "shadows",
        what: "the atlas, virtual pages and shadow rays from 16 to 16,384 lights at 1080p",
        full: &[
            "shadows",
            "--lights",
            "16,64,256,1024,4096,16384",
            "--width",
            "1920",
            "--height",
            "1080",
        ],
        quick: &[
            "shadows",
            "--scene",
            "cubes",
            "--lights",
            "16,64",
            "--width",
            "96",
            "--height",
            "54",
            "--repeats",
            "1",
            "--warmup",
            "0",
        ],
    },
];

/// Runs `manyshadows bench suite`.
pub fn suite(args: &SuiteArgs) -> Result<()> {
    let exe = std::env::current_exe().context("finding this program to run the sections")?;
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    let mut table = format!(
        "== bench suite{}: {} sections, each its own bench command (below); absolute times \
         are this adapter's only\n",
        if args.quick {
            " --quick (tiny sizes, not a measurement)"
        } else {
            ""
        },
        SECTIONS.len()
    );
    let mut sections = Vec::new();
    for (k, s) in SECTIONS.iter().enumerate() {
        let dir = args.out_dir.join(s.name);
        let mut argv: Vec<String> = if args.quick { s.quick } else { s.full }
            .iter()
            .map(|a| a.to_string())
            .collect();
        argv.extend(["--out-dir".into(), dir.display().to_string()]);
        if let Some(b) = &args.backend {
            argv.extend(["--backend".into(), b.clone()]);
        }
        if let Some(a) = &args.adapter {
            argv.extend(["--adapter".into(), a.clone()]);
        }
        eprintln!(
            "[{}/{}] manyshadows bench {} — {}",
            k + 1,
            SECTIONS.len(),
            argv.join(" "),
            s.what
        );
        let status = Command::new(&exe)
            .arg("bench")
            .args(&argv)
            .status()
            .with_context(|| format!("running bench {}", s.name))?;
        if !status.success() {
            bail!(
                "section {} (manyshadows bench {}) failed with {status}; the sections before it are in {}",
                s.name,
                argv.join(" "),
                args.out_dir.display()
            );
        }
        let text = read(&dir.join("results.txt"))?;
        let json: serde_json::Value = serde_json::from_str(&read(&dir.join("results.json"))?)
            .with_context(|| format!("reading {}", dir.join("results.json").display()))?;
        table += &format!(
            "\n## {} — {}\n$ manyshadows bench {}\n{text}",
            s.name,
            s.what,
            argv.join(" ")
        );
        sections.push(serde_json::json!({
            "name": s.name,
            "what": s.what,
            "args": argv,
            "results": json,
        }));
    }
    let adapter = sections
        .first()
        .and_then(|s| s["results"]["adapter"].as_str())
        .unwrap_or("?")
        .to_string();
    let txt = args.out_dir.join("suite.txt");
    std::fs::write(&txt, &table).with_context(|| format!("writing {}", txt.display()))?;
    let json = args.out_dir.join("suite.json");
    let all = serde_json::json!({ "adapter": adapter, "quick": args.quick, "sections": sections });
    std::fs::write(&json, serde_json::to_string_pretty(&all)?)
        .with_context(|| format!("writing {}", json.display()))?;
    println!("{table}");
    println!("wrote {}\nwrote {}", txt.display(), json.display());
    Ok(())
}

fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))
}
