//! Fuzzing the `.msvis` visibility-file reader (`VisibilityMask::read_raw`) on stable Rust
//! with proptest, as `manyshadows-scene`'s `fuzz.rs` does for the mesh and scene loaders.
//!
//! Inputs: valid files of random masks (round trip must be exact), the same files mutated
//! (bytes flipped or overwritten, header fields replaced by huge, zero and off-by-one values,
//! truncation, extension), and noise behind the magic. Every input must either read back as a
//! mask whose fields agree with each other and with the bytes (writing it again gives the
//! input), or be refused with a non-empty message; nothing may panic, and nothing is
//! allocated beyond the input's own size (a header claiming 2^32 × 2^32 pixels is an error).
//! No GPU is needed.
//!
//! `MANYSHADOWS_FUZZ_CASES` (default 2,000 here: well under a second) and
//! `MANYSHADOWS_FUZZ_SECONDS` work as for the loader fuzzing.

use std::time::{Duration, Instant};

use manyshadows::VisibilityMask;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

fn cases() -> u32 {
    std::env::var("MANYSHADOWS_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2000)
}

fn seconds() -> Option<u64> {
    std::env::var("MANYSHADOWS_FUZZ_SECONDS")
        .ok()
        .and_then(|v| v.parse().ok())
}

fn mask(width: u32, height: u32, lights: u32, words: &[u32]) -> VisibilityMask {
    let wpp = lights.div_ceil(32).max(1);
    let n = (width * height * wpp) as usize;
    VisibilityMask {
        width,
        height,
        lights,
        words_per_pixel: wpp,
        words: (0..n).map(|i| words[i % words.len()]).collect(),
    }
}

fn bytes_of(m: &VisibilityMask) -> Vec<u8> {
    let mut out = Vec::new();
    m.write_raw(&mut out).unwrap();
    out
}

/// Values that break size arithmetic.
const FIELDS: &[u32] = &[
    0,
    1,
    2,
    31,
    32,
    33,
    65535,
    65536,
    1 << 31,
    u32::MAX - 1,
    u32::MAX,
];

#[derive(Clone, Debug)]
enum Mutation {
    Flip(usize, u8),
    Field(usize, u32),
    Truncate(usize),
    Extend(Vec<u8>),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::Flip(i, b)),
        (
            0..4usize,
            prop_oneof![prop::sample::select(FIELDS), any::<u32>()]
        )
            .prop_map(|(f, v)| Mutation::Field(f, v)),
        any::<usize>().prop_map(Mutation::Truncate),
        prop::collection::vec(any::<u8>(), 1..16).prop_map(Mutation::Extend),
    ]
}

fn apply(mut b: Vec<u8>, m: &Mutation) -> Vec<u8> {
    match m {
        Mutation::Flip(i, x) if !b.is_empty() => {
            let i = i % b.len();
            b[i] ^= x | 1;
        }
        Mutation::Field(f, v) if b.len() >= 24 => {
            b[8 + 4 * f..12 + 4 * f].copy_from_slice(&v.to_le_bytes());
        }
        Mutation::Truncate(n) => b.truncate(n % (b.len() + 1)),
        Mutation::Extend(tail) => b.extend_from_slice(tail),
        _ => {}
    }
    b
}

/// The contract for one input.
fn check(input: &[u8]) -> Result<(), TestCaseError> {
    let read = std::panic::catch_unwind(|| VisibilityMask::read_raw(input));
    let Ok(read) = read else {
        return Err(TestCaseError::fail(format!(
            "read_raw panicked on {} bytes: {:02x?}",
            input.len(),
            &input[..input.len().min(40)]
        )));
    };
    match read {
        Ok(m) => {
            let wpp = m.lights.div_ceil(32).max(1);
            prop_assert_eq!(m.words_per_pixel, wpp);
            prop_assert_eq!(
                m.words.len() as u64,
                m.width as u64 * m.height as u64 * wpp as u64
            );
            prop_assert_eq!(bytes_of(&m), input.to_vec());
            // Every accessor works on what was read.
            for light in 0..m.lights.min(40) {
                prop_assert_eq!(
                    m.light_image(light).len() as u64,
                    m.width as u64 * m.height as u64
                );
            }
        }
        Err(e) => prop_assert!(!e.to_string().is_empty(), "empty error message"),
    }
    Ok(())
}

#[test]
fn msvis_reader_survives_generated_and_mutated_files() {
    let config = Config {
        cases: cases(),
        failure_persistence: None,
        ..Config::default()
    };
    let strategy = (
        (0u32..24, 0u32..24, 0u32..100),
        prop::collection::vec(any::<u32>(), 1..8),
        prop::collection::vec(mutation(), 0..6),
        prop::collection::vec(any::<u8>(), 0..96),
        0u8..8,
    );
    let mut streams = TestRunner::new(config.clone());
    let started = Instant::now();
    let (mut total, mut accepted) = (0u64, 0u64);
    loop {
        let ok = std::cell::Cell::new(0u64);
        TestRunner::new_with_rng(config.clone(), streams.new_rng())
            .run(
                &strategy,
                |((w, h, lights), words, mutations, noise, kind)| {
                    let valid = bytes_of(&mask(w, h, lights, &words));
                    let input = match kind {
                        // Noise behind the magic.
                        0 => [b"MSVIS001".as_slice(), &noise].concat(),
                        // The valid file, unchanged: it must read back exactly.
                        1 => {
                            let m = VisibilityMask::read_raw(&valid)
                                .map_err(|e| TestCaseError::fail(format!("valid file: {e}")))?;
                            prop_assert_eq!(m, mask(w, h, lights, &words));
                            valid
                        }
                        _ => mutations.iter().fold(valid, apply),
                    };
                    check(&input)?;
                    if VisibilityMask::read_raw(&input).is_ok() {
                        ok.set(ok.get() + 1);
                    }
                    Ok(())
                },
            )
            .unwrap_or_else(|e| panic!("msvis: {e}"));
        total += u64::from(cases());
        accepted += ok.get();
        if seconds().is_none_or(|s| started.elapsed() >= Duration::from_secs(s)) {
            break;
        }
    }
    eprintln!(
        "msvis: {total} inputs in {:.1} s, {accepted} read as masks, the rest refused",
        started.elapsed().as_secs_f64()
    );
    // The generator reaches both outcomes (a fuzzer that only ever sees errors tests nothing).
    assert!(
        accepted > 0 && accepted < total,
        "{accepted} of {total} accepted"
    );
}

/// Headers whose sizes overflow or outgrow the bytes present are refused before allocating.
#[test]
fn huge_headers_are_refused_without_allocating() {
    for (w, h, lights) in [
        (u32::MAX, u32::MAX, u32::MAX),
        (1 << 16, 1 << 16, 1 << 20),
        (u32::MAX, 1, 1),
    ] {
        let mut b = b"MSVIS001".to_vec();
        for v in [w, h, lights, lights.div_ceil(32).max(1)] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let err = VisibilityMask::read_raw(&b).expect_err("a header with no words");
        let err = err.to_string();
        assert!(err.contains("overflow") || err.contains("need"), "{err}");
    }
}
