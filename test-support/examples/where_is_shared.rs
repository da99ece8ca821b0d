//! Prints where sornav looks for the shared real data and what it finds there.
//!
//! `cargo run -p sornav-test-support --example where_is_shared`
fn main() {
    let root = sornav_test_support::shared_root();
    println!("shared root: {}", root.display());
    for rel in [
        "tsplib",
        "tsp-fuel",
        "hm3d-sem-stats",
        "sh3d-homes",
        "objectnav-val-mini",
    ] {
        let path = root.join("data").join(rel);
        let entries = std::fs::read_dir(&path).map(|d| d.count()).unwrap_or(0);
        let state = if path.is_dir() { "present" } else { "missing" };
        println!("  {rel:<20} {state:<8} {entries} entries");
    }
}
