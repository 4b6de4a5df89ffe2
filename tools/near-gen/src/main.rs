//! Rewrites `src/near/tables.rs` (run from the workspace root or give the path).

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "src/near/tables.rs".into());
    let text = hydrorattle_near_gen::emit::source();
    std::fs::write(&path, text).expect("writing the tables");
    eprintln!("wrote {path}");
}
