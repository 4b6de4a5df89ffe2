//! Rewrites `src/near/tables.rs` and `src/near/wall_table.rs` (run from the workspace root,
//! or give both paths).

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().unwrap_or_else(|| "src/near/tables.rs".into());
    let wall = args
        .next()
        .unwrap_or_else(|| "src/near/wall_table.rs".into());
    std::fs::write(&path, hydrorattle_near_gen::emit::source()).expect("writing the tables");
    eprintln!("wrote {path}");
    std::fs::write(&wall, hydrorattle_near_gen::emit::wall_source())
        .expect("writing the wall table");
    eprintln!("wrote {wall}");
}
