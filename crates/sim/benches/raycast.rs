//! Ray casting benchmark (filled in with the map loader).
fn main() {}
