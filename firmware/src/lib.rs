//! Cortex-M4F firmware for the Figure 1 (c) chain, one binary per method (`src/bin/`).
//!
//! Each binary runs [`hydrorattle_scene::STEPS`] steps in `f32` from statics, then prints
//! over semihosting the summary line the host check prints (digest of the positions'
//! bits and the last `StepReport`, compared by `ci.sh`) and a cost line: instructions
//! per step (SysTick under `qemu-system-arm -icount shift=0`), peak stack (cortex-m-rt
//! paints the stack; we find the lowest scrubbed word) and statics.
//!
//! Stack overflow faults instead of corrupting: flip-link links the stack below the
//! statics, and [`guard_below_stack`] makes the memory under it inaccessible (QEMU's
//! mps2 boards map a write-ignoring reserved region there; a real part would fault on
//! its own). The HardFault handler moves the stack pointer back into RAM, reports and
//! exits non-zero.
#![no_std]

use core::arch::{asm, naked_asm};
use core::fmt::{self, Write};
use core::panic::PanicInfo;

use cortex_m::peripheral::{MPU, SCB, SYST, syst::SystClkSource};
use cortex_m_semihosting::{debug, hio};
use hydrorattle::{Params, ParticleSet, Workspace};
use hydrorattle_scene::{self as scene, N};

include!(concat!(env!("OUT_DIR"), "/geometry.rs"));

pub use cortex_m_rt::entry;

unsafe extern "C" {
    // Linker symbols (cortex-m-rt's link.x; flip-link moves the stack's two).
    static _stack_start: u32;
    static _stack_end: u32;
    static __sbss: u32;
    static __ebss: u32;
    static __sdata: u32;
    static __edata: u32;
}

/// The word cortex-m-rt paints the stack with (feature `paint-stack`).
const PAINT: u32 = 0xcccc_cccc;
/// Instructions of the SysTick calibration loop (two per iteration).
const CALIBRATION: u32 = 1_000_000;

/// One firmware binary: a `main` that runs `$method` (with thermal noise if
/// `$brownian`) from statics sized by the method's `const` layout.
#[macro_export]
macro_rules! firmware {
    ($name:literal, $method:expr, $rotation:expr) => {
        $crate::firmware!($name, $method, $rotation, false);
    };
    ($name:literal, $method:expr, $rotation:expr, $brownian:expr) => {
        const L: hydrorattle::Layout = {
            let (n, b) = (hydrorattle_scene::N, hydrorattle_scene::B);
            let l = hydrorattle::Layout::with_solver(
                $method,
                $rotation,
                hydrorattle::SolverKind::Newton,
                n,
                b,
            );
            if $brownian {
                l.thermal($method, n, b)
            } else {
                l
            }
        };
        type Store =
            hydrorattle::Storage<f32, { L.blocks }, { L.vectors }, { L.scalars }, { L.indices }>;

        #[$crate::entry]
        fn main() -> ! {
            // `entry` turns these into `&'static mut`: statics, not stack.
            static mut STORE: Store = Store::new();
            static mut CHAIN: hydrorattle::ParticleSet<f32, { hydrorattle_scene::N }> =
                hydrorattle::ParticleSet::new();
            // A constant the compiler can see through: only this method is linked.
            static PARAMS: hydrorattle::Params<f32> =
                hydrorattle_scene::params_f32($method, $rotation, $brownian);
            $crate::run($name, &PARAMS, &mut STORE.workspace(), CHAIN)
        }
    };
}

/// Runs the scene with `p`, prints the summary and cost lines, exits QEMU. Inlined
/// into `main`, where `p` is a constant `static`: the compiler folds the method and
/// solver choices and links only the integrator this binary runs.
#[inline(always)]
pub fn run(
    name: &str,
    p: &Params<f32>,
    ws: &mut Workspace<'_, f32>,
    ps: &mut ParticleSet<f32, N>,
) -> ! {
    guard_below_stack();
    let mut cp = cortex_m::Peripherals::take().unwrap_or_else(|| fail("peripherals taken"));
    start_clock(&mut cp.SYST);
    let calibration = time(|| spin(CALIBRATION / 2));
    let bonds = scene::chain_from(&GEOMETRY, ps).unwrap_or_else(|_| fail("scene"));
    let mut ticks = 0u64;
    let mut t0 = 0;
    let outcome = scene::run(ps, &bonds, p, ws, scene::STEPS, |before| {
        let now = SYST::get_current();
        if before {
            t0 = now;
        } else {
            ticks += u64::from(elapsed(t0, now));
        }
    });
    let mut out = Host;
    let _ = scene::summary(&mut out, p, &outcome);
    // The divisor fits 32 bits: the calibration reads a 24-bit counter. Two `u64`
    // figures, divided and printed without core's `u64` division and formatting
    // (`scene::decimal`): on 32-bit Arm those link a software 64-bit division, about
    // 1.7 kB of flash that no step needs.
    const _: () = assert!(0x00ff_ffff * (scene::STEPS as u64) <= u32::MAX as u64);
    let per_step = scene::div_rem(
        ticks * u64::from(CALIBRATION),
        calibration.max(1) * scene::STEPS,
    )
    .0;
    let (bss, data, stack) = (
        span(&raw const __sbss, &raw const __ebss),
        data_size(),
        peak(),
    );
    let _ = out.write_str("cost ");
    let _ = out.write_str(name);
    let _ = out.write_str(" instructions_per_step=");
    let _ = scene::decimal(&mut out, per_step);
    let _ = out.write_str(" ticks=");
    let _ = scene::decimal(&mut out, ticks);
    let _ = writeln!(
        out,
        " calibration_ticks={calibration} stack_peak={stack} bss={bss} data={data} \
         ram_needed={}",
        bss + data + stack
    );
    debug::exit(if outcome.is_ok() {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    fail("semihosting exit returned")
}

/// Semihosting stdout as a `fmt::Write` (opened per write: no state to keep).
struct Host;

impl Write for Host {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let mut h = hio::hstdout().map_err(|_| fmt::Error)?;
        h.write_all(s.as_bytes()).map_err(|_| fmt::Error)
    }
}

/// Prints `why` and exits QEMU with a failure status.
fn fail(why: &str) -> ! {
    // Strings go out through `write_str`: `{}` on a `&str` links core's padding code.
    let _ = Host.write_str("firmware error: ");
    let _ = Host.write_str(why);
    let _ = Host.write_str("\n");
    debug::exit(debug::EXIT_FAILURE);
    cortex_m::asm::udf()
}

/// Starts SysTick as a free-running 24-bit down-counter on the core clock.
fn start_clock(syst: &mut SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(0x00ff_ffff);
    syst.clear_current();
    syst.enable_counter();
}

/// Ticks taken by `f` (at most 2^24 - 1).
fn time(f: impl FnOnce()) -> u32 {
    let t0 = SYST::get_current();
    f();
    elapsed(t0, SYST::get_current())
}

/// Ticks from `t0` to `t1` of the down-counter, across one wrap.
fn elapsed(t0: u32, t1: u32) -> u32 {
    t0.wrapping_sub(t1) & 0x00ff_ffff
}

/// Exactly `2 n` instructions (`subs`, `bne`), for calibrating ticks to instructions.
fn spin(n: u32) {
    // SAFETY: a register-only countdown loop.
    unsafe {
        asm!("1:", "subs {0}, #1", "bne 1b", inout(reg) n => _, options(nomem, nostack));
    }
}

fn span(a: *const u32, b: *const u32) -> usize {
    b as usize - a as usize
}

fn data_size() -> usize {
    span(&raw const __sdata, &raw const __edata)
}

/// Bytes of stack ever used: from the top down to the lowest word no longer painted.
fn peak() -> usize {
    let (bottom, top) = (
        &raw const _stack_end as usize,
        &raw const _stack_start as usize,
    );
    let mut a = bottom;
    // SAFETY: [bottom, top) is the stack region the linker laid out, word aligned.
    while a < top && unsafe { core::ptr::read_volatile(a as *const u32) } == PAINT {
        a += 4;
    }
    top - a
}

/// Makes the memory just below the stack inaccessible with an MPU region (up to 1 MiB,
/// as large as the alignment of the stack's bottom allows), so the first write past
/// the stack faults even where the bus would ignore it.
fn guard_below_stack() {
    let bottom = &raw const _stack_end as u32;
    let size = (bottom & bottom.wrapping_neg()).min(1 << 20);
    if size < 32 {
        return;
    }
    // SAFETY: the MPU is ours alone; region 0 only ever covers memory below the stack.
    unsafe {
        let mpu = &*MPU::PTR;
        mpu.rnr.write(0);
        mpu.rbar.write(bottom - size);
        // XN, AP = no access, SIZE = log2(size) - 1, enabled.
        mpu.rasr
            .write((1 << 28) | ((size.trailing_zeros() - 1) << 1) | 1);
        // Enabled, with the default map as background for privileged code; off in
        // HardFault, whose handler then runs on a stack it has moved back into RAM.
        mpu.ctrl.write(0b101);
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
}

/// The HardFault vector: a stack overflow leaves the stack pointer outside RAM, so move
/// it back to the top of the stack before running any Rust.
///
/// # Safety
/// Only the processor calls it, as an exception handler; it never returns.
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn HardFault() -> ! {
    naked_asm!(
        "ldr r0, =_stack_start",
        "msr msp, r0",
        "b {report}",
        report = sym fault_report,
    )
}

extern "C" fn fault_report() -> ! {
    // SAFETY: reads of the fault status registers.
    let (cfsr, mmfar) = unsafe { ((*SCB::PTR).cfsr.read(), (*SCB::PTR).mmfar.read()) };
    let bottom = &raw const _stack_end as u32;
    let overflow = cfsr & (1 << 7) != 0 && mmfar < bottom;
    let what = if overflow {
        "stack overflow (write below the stack)"
    } else {
        "fault"
    };
    let _ = Host.write_str("HardFault: ");
    let _ = Host.write_str(what);
    let _ = writeln!(Host, "; CFSR={cfsr:#010x} MMFAR={mmfar:#010x}");
    debug::exit(debug::EXIT_FAILURE);
    cortex_m::asm::udf()
}

#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    // The location only: formatting the message would link core's padding and
    // integer formatting for a path that never runs on valid input (about 1 KB).
    if let Some(at) = info.location() {
        let _ = Host.write_str("panic at ");
        let _ = Host.write_str(at.file());
        let _ = writeln!(Host, ":{}", at.line());
    }
    debug::exit(debug::EXIT_FAILURE);
    cortex_m::asm::udf()
}
