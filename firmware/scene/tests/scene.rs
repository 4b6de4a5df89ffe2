//! The scene as the firmware runs it: constant parameters equal to the kernel's
//! defaults with the scene's changes, a chain that satisfies its bonds, and a run that
//! gives the same bits twice.

use hydrorattle::{Layout, NoiseSqrt, ParticleSet};
use hydrorattle_heap::Buffers;
use hydrorattle_scene::{B, N, NOISE_SQRT, RUNS, STEPS, chain, digest, params, params_f32, run};

#[test]
fn constant_parameters_match_the_kernel_defaults() {
    for (name, method, rotation, brownian) in RUNS {
        assert_eq!(
            params_f32(method, rotation, brownian),
            params::<f32>(method, rotation, brownian),
            "{name}"
        );
    }
}

/// The thermal runs name the square root the kernel's default picks at `N` beads
/// (so the firmware links one path): the same bits as the default.
#[test]
fn the_named_noise_square_root_is_the_default_s_choice() {
    assert!(!NoiseSqrt::Auto.lanczos(N));
    assert_eq!(NOISE_SQRT, NoiseSqrt::Cholesky);
    let thermal = |sqrt: NoiseSqrt| {
        let mut ps = ParticleSet::<f32, N>::new();
        let bonds = chain(&mut ps).unwrap();
        let mut p = params::<f32>(hydrorattle::Method::Overdamped, false, true);
        p.noise_sqrt = sqrt;
        let mut store = Buffers::<f32>::new(Layout::for_params(&p, N, B));
        run(&mut ps, &bonds, &p, &mut store.workspace(), STEPS, |_| {}).unwrap()
    };
    let named = thermal(NOISE_SQRT);
    assert_eq!(named, thermal(NoiseSqrt::Auto));
    assert_eq!(named.report.noise_iterations, 0, "Cholesky, not Lanczos");
    assert_ne!(named, thermal(NoiseSqrt::Lanczos));
}

#[test]
fn chain_holds_its_bonds() {
    let mut ps = ParticleSet::<f64, N>::new();
    let bonds = chain(&mut ps).unwrap();
    assert_eq!((ps.len(), bonds.len()), (N, B));
    bonds.check_satisfied(&ps.pos[..N], 1e-12).unwrap();
    ps.validate(false).unwrap();
}

#[test]
fn runs_are_deterministic() {
    let once = || {
        let mut ps = ParticleSet::<f32, N>::new();
        let bonds = chain(&mut ps).unwrap();
        let p = params::<f32>(hydrorattle::Method::Overdamped, false, false);
        let mut store = Buffers::<f32>::new(Layout::for_params(&p, N, B));
        run(&mut ps, &bonds, &p, &mut store.workspace(), 20, |_| {}).unwrap()
    };
    let (a, b) = (once(), once());
    assert_eq!(a, b);
    assert_ne!(a.digest, digest::<f32>(&[]));
}

/// With `HYDRORATTLE_FIRMWARE_OUTPUT` naming a file of firmware output (QEMU's
/// semihosting stdout, as `ci.sh` saves it), every summary line in it must equal the
/// line computed here: the same bits on x86_64 and on the Cortex-M4.
#[test]
fn firmware_output_matches_the_host() {
    let Ok(path) = std::env::var("HYDRORATTLE_FIRMWARE_OUTPUT") else {
        eprintln!("HYDRORATTLE_FIRMWARE_OUTPUT not set: nothing to compare");
        return;
    };
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("figure1c "))
        .collect();
    assert!(!lines.is_empty(), "{path} holds no summary line");
    let host = hydrorattle_scene::host_summaries(&[]);
    for line in lines {
        assert!(
            host.lines().any(|h| h == line),
            "firmware: {line}\nhost:\n{host}"
        );
    }
}

/// The firmware's `u64` division and decimal printing against the host's `/`, `%` and
/// `{}`: powers of two and ten about every word boundary, the extremes, and a spread.
#[test]
fn wide_division_and_decimal_match_u64() {
    use hydrorattle_scene::{decimal, div_rem};
    let mut ns = vec![0, 1, 9, 10, 11, u64::MAX, u64::MAX - 1];
    for k in 0..64 {
        ns.extend([1u64 << k, (1u64 << k) - 1, (1u64 << k) + 1]);
    }
    for k in 0..20 {
        let p = 10u64.pow(k);
        ns.extend([p, p - 1, p + 1]);
    }
    // SplitMix64's increment as a stride: a spread of every magnitude's bits.
    let mut x = 0u64;
    for _ in 0..1000 {
        x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
        ns.extend([x, x >> 17, x >> 40]);
    }
    let ds = [
        1u32,
        2,
        3,
        7,
        10,
        200,
        1_000_000,
        199_999_999,
        0x00ff_ffff * 200,
        u32::MAX,
    ];
    for &n in &ns {
        for &d in &ds {
            let want = (n / u64::from(d), (n % u64::from(d)) as u32);
            assert_eq!(div_rem(n, d), want, "{n} / {d}");
        }
        let mut s = String::new();
        decimal(&mut s, n).unwrap();
        assert_eq!(s, n.to_string());
    }
    assert_eq!(div_rem(7, 0), (7, 0), "a zero divisor divides by 1");
}
