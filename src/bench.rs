//! `wetgran bench`: engine speed on the reference systems of docs/performance.md.
pub fn run(which: &str, _repeat: usize, _scale: f64) -> Result<(), String> {
    Err(format!("unknown benchmark `{which}`"))
}
