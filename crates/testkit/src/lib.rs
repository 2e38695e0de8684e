//! What the test suites share about the backend they run on.
//!
//! `cargo xtask test` knows what each backend of its run must offer (the Vulkan run on Mesa 25's
//! lavapipe: ray queries, multiview, clip distances; the OpenGL run: what llvmpipe's GL
//! offers) and says so in [`EXPECT_VAR`], a comma-separated list of requirement names as wgpu
//! spells them (`EXPERIMENTAL_RAY_QUERY`, `MULTIVIEW`, `CLIP_DISTANCES`). A test that finds
//! something refused for lack of a requirement calls [`refused`]: where the backend must offer
//! it, the test fails, saying what to install; elsewhere the refusal is what the test can check,
//! and it is written to the file [`REFUSALS_VAR`] names, so that the run's summary lists every
//! test that checked a refusal instead of running.
//!
//! Without the test command (plain `cargo test`) nothing is expected and refusals are only
//! printed.

use std::io::Write;

/// The environment variable with the requirements this run's backend must offer.
pub const EXPECT_VAR: &str = "MANYSHADOWS_EXPECT";

/// The environment variable naming the file refusals are appended to (one line each: the
/// test, the requirement, the message's first line, tab-separated).
pub const REFUSALS_VAR: &str = "MANYSHADOWS_REFUSALS";

/// The requirements the test command says this backend must offer (empty without it).
pub fn expected() -> Vec<String> {
    std::env::var(EXPECT_VAR)
        .map(|v| parse_list(&v))
        .unwrap_or_default()
}

fn parse_list(v: &str) -> Vec<String> {
    v.split(',')
        .map(|s| s.trim().to_ascii_uppercase())
        .filter(|s| !s.is_empty())
        .collect()
}

/// Whether the test command says this backend must offer `need` (a name as wgpu spells it).
pub fn must_offer(need: &str) -> bool {
    let need = need.trim().to_ascii_uppercase();
    expected().contains(&need)
}

/// The name of the running test (libtest names each test's thread after it).
pub fn test_name() -> String {
    std::thread::current()
        .name()
        .unwrap_or("(unnamed test)")
        .to_string()
}

/// A test found something refused for lack of `need` (`message`: the refusal). Panics where
/// the backend must offer `need` (the test would otherwise pass without running what it
/// claims); otherwise records the test as one that checked a refusal instead of running.
#[track_caller]
pub fn refused(need: &str, message: &str) {
    if must_offer(need) {
        panic!(
            "refused for lack of {need}, which the test command says this backend must offer \
             ({EXPECT_VAR}={}): {message}\n\
             On Linux the Vulkan run needs Mesa 25's lavapipe (Debian 12: \
             `apt-get install -t bookworm-backports mesa-vulkan-drivers`); `cargo xtask test` \
             installs it.",
            std::env::var(EXPECT_VAR).unwrap_or_default()
        );
    }
    let first = message.lines().next().unwrap_or("").replace('\t', " ");
    eprintln!("checked a refusal instead of running (no {need}): {first}");
    record(&format!("{}\t{need}\t{first}\n", test_name()));
}

fn record(line: &str) {
    let Some(path) = std::env::var_os(REFUSALS_VAR) else {
        return;
    };
    // One write per line with O_APPEND: lines from parallel tests and binaries do not mix.
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path);
    match file {
        Ok(mut f) => {
            if let Err(e) = f.write_all(line.as_bytes()) {
                panic!(
                    "cannot append to {}: {e}",
                    std::path::Path::new(&path).display()
                );
            }
        }
        Err(e) => panic!("cannot open {}: {e}", std::path::Path::new(&path).display()),
    }
}

/// The refusals a file of [`REFUSALS_VAR`] holds: (test, requirement, message), sorted and
/// without repeats (a test may check the same refusal more than once).
pub fn read_refusals(text: &str) -> Vec<(String, String, String)> {
    let mut out: Vec<(String, String, String)> = text
        .lines()
        .filter_map(|l| {
            let mut parts = l.splitn(3, '\t');
            Some((
                parts.next()?.to_string(),
                parts.next()?.to_string(),
                parts.next().unwrap_or("").to_string(),
            ))
        })
        .collect();
    out.sort();
    out.dedup_by(|a, b| a.0 == b.0 && a.1 == b.1);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_parse_trimmed_and_upper_case() {
        assert_eq!(
            parse_list(" experimental_ray_query, MULTIVIEW ,,"),
            vec!["EXPERIMENTAL_RAY_QUERY", "MULTIVIEW"]
        );
        assert!(parse_list("").is_empty());
    }

    #[test]
    fn refusal_lines_read_back_once_per_test_and_need() {
        let text = "b\tMULTIVIEW\tno multiview\na\tEXPERIMENTAL_RAY_QUERY\tno rays\n\
                    a\tEXPERIMENTAL_RAY_QUERY\tno rays again\nbroken line\n";
        let r = read_refusals(text);
        assert_eq!(r.len(), 2, "{r:?}");
        assert_eq!(r[0].0, "a");
        assert_eq!(
            r[1],
            ("b".into(), "MULTIVIEW".into(), "no multiview".into())
        );
    }
}
