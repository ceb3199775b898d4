//! How long one load takes when it misses, against how much memory a
//! program touches: a chase of pointers in a random cycle through one
//! 64-byte line after another of a buffer of 1, 2, … 128 MiB (each load's
//! address is the previous load's value, so no two overlap). Where the time
//! jumps is how much of the last-level cache this process really gets on
//! this machine (on a VM, less than `lscpu` says when neighbours share it),
//! which decides how large the renderer's hot data may be
//! (`docs/benchmarks.md`, "The mesh's hot memory").
//!
//! ```text
//! cargo run --release -p fgf-render --example mem_latency
//! ```
//!
//! Prints one line per size: MiB, nanoseconds per load.

use std::io::Write;
use std::time::Instant;

fn main() {
    // A fixed generator (xorshift64*): the same cycle on every run.
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        state.wrapping_mul(0x2545_F491_4F6C_DD1D)
    };
    const LINE: usize = 64 / std::mem::size_of::<usize>();
    let mut mib = 1usize;
    while mib <= 128 {
        let lines = mib * 1024 * 1024 / 64;
        // A random cyclic order of the lines (Fisher–Yates), then each
        // line's first word holds the index of the next line's.
        let mut order: Vec<usize> = (0..lines).collect();
        for i in (1..lines).rev() {
            order.swap(i, (next() % (i as u64 + 1)) as usize);
        }
        let mut buf = vec![0usize; lines * LINE];
        for k in 0..lines {
            buf[order[k] * LINE] = order[(k + 1) % lines] * LINE;
        }
        let mut p = order[0] * LINE;
        // One untimed lap, then 2·10⁷ timed loads.
        for _ in 0..lines {
            p = buf[p];
        }
        let loads = 20_000_000;
        let t = Instant::now();
        for _ in 0..loads {
            p = buf[p];
        }
        let ns = t.elapsed().as_secs_f64() * 1e9 / loads as f64;
        std::hint::black_box(p);
        // (A closed pipe, as under `head`, ends the run quietly.)
        if writeln!(std::io::stdout(), "{mib:>4} MiB: {ns:6.1} ns per load").is_err() {
            return;
        }
        mib *= 2;
    }
}
