//! Runs one fuzz target on every file of a folder (a corpus or an AFL
//! queue), in process, and prints the slowest inputs: where a target spends
//! its time, and which inputs hang.
//!
//! ```text
//! cargo run --release -p mp-fuzz --example replay -- npz fuzz/out/npz/default/queue [N]
//! ```

use std::time::Instant;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

fn main() -> Res<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(name), Some(dir)) = (args.first(), args.get(1)) else {
        return Err("usage: replay TARGET DIR [N]".into());
    };
    let show: usize = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(10);
    let Some(target) = mp_fuzz::target(name) else {
        return Err(format!("unknown target `{name}`").into());
    };
    let mut times = Vec::new();
    let mut total = 0.0;
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if !path.is_file() {
            continue;
        }
        let data = std::fs::read(&path)?;
        let t0 = Instant::now();
        target(&data);
        let s = t0.elapsed().as_secs_f64();
        total += s;
        times.push((s, data.len(), path));
    }
    times.sort_by(|a, b| b.0.total_cmp(&a.0));
    println!(
        "{name}: {} inputs, {:.3} s in all, {:.3} ms each on average",
        times.len(),
        total,
        1e3 * total / times.len().max(1) as f64
    );
    for (s, len, path) in times.iter().take(show) {
        println!("{:9.3} ms  {len:7} bytes  {}", 1e3 * s, path.display());
    }
    Ok(())
}
