use situate::manager::ExecutorKind;
use situate_bench::skills;
use std::time::Instant;

fn own_ticks() -> u64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap();
    let after = s.rsplit_once(')').unwrap().1;
    let f: Vec<u64> = after.split_whitespace().map(|x| x.parse().unwrap_or(0)).collect();
    f[11] + f[12]
}

fn main() {
    raw();
    let iters: u64 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(40_000);
    for ex in [ExecutorKind::Serial, ExecutorKind::Parallel, ExecutorKind::Serial, ExecutorKind::Parallel] {
        let mut spec = skills::robot("p").executor(ex, Some(2));
        spec.skills = skills::workers(8, iters);
        let mut m = skills::build(&spec);
        for _ in 0..50 {
            m.cycle();
        }
        let (t0, c0) = (Instant::now(), own_ticks());
        for _ in 0..1000 {
            m.cycle();
        }
        let wall = t0.elapsed().as_secs_f64();
        let cpu = (own_ticks() - c0) as f64 / 100.0;
        println!("{ex:?}: wall {:.0} µs/cycle, cpu {:.0} µs/cycle, cpu/wall {:.2}", wall * 1e3, cpu * 1e3, cpu / wall);
    }
}

#[allow(dead_code)]
pub fn raw() {
    let iters = 40_000u64;
    let t0 = Instant::now();
    let c0 = own_ticks();
    let hs: Vec<_> = (0..2)
        .map(|_| {
            std::thread::spawn(move || {
                let mut x = 1.0;
                for _ in 0..4000 {
                    x = skills::spin(iters, x);
                }
                x
            })
        })
        .collect();
    for h in hs {
        std::hint::black_box(h.join().unwrap());
    }
    let wall = t0.elapsed().as_secs_f64();
    let cpu = (own_ticks() - c0) as f64 / 100.0;
    println!("2 raw threads: wall {wall:.2} s, cpu {cpu:.2} s, cpu/wall {:.2}", cpu / wall);
}
