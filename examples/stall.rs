use wetgran::scene::Scene;
use wetgran::sim::event_driven::Engine;
fn main() {
    let scene = Scene::load(std::path::Path::new("/tmp/s.toml")).unwrap();
    let mut e = Engine::<2, true, true>::new(&scene);
    let mut prev = String::new();
    loop {
        let n = e.counts().total();
        let ev = e.describe_next_event();
        e.run_until(100.0, Some(n + 1));
        let d = format!("   {}\n   {}", e.describe_particle(584), e.describe_particle(585));
        if d != prev { println!("{n}: {ev}\n{d}"); prev = d; }
        if let Err(msg) = e.sanity_check() {
            println!("after event {}: {msg}", e.counts().total());
            break;
        }
    }
}
