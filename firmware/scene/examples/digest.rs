//! The host side of the host-versus-Cortex-M check: prints, for every firmware binary
//! (or the ones named), the summary line the firmware prints over semihosting.
//! `cargo run --release --features alloc --example digest [NAME ...]`.

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let only: Vec<&str> = args.iter().map(String::as_str).collect();
    print!("{}", hydrorattle_scene::host_summaries(&only));
}
