//! The generator's first family of buildings (`--family 1`), frozen as it
//! was before issue 37: the same seed gives the same building as then (the
//! comment block of features aside), so buildings named by their seed in
//! tests and reports stay what they were. Its lobby has the call button
//! across from the entry and cars beside the button or next to it on the
//! side walls; the corridors' ends are T junctions; no box is placed beside
//! the office barcode on purpose. The default, `--family 2`
//! ([`super::build`]), draws from the whole space `docs/maps.md` allows.

use super::corridor::{clutter, door_margins, features, hdoor, junction_kinds, junction_list, vdoor, Feature, Run};
use super::route::{flip_word, junction_step, office_steps, turn};
use super::*;

/// What a family-1 building drew (no random number is drawn here).
fn features_of(
    b: &Building,
    walls_of: &[char],
    widths: &[i64],
    (stub, side_corridor): (bool, bool),
    passed: Vec<&'static str>,
) -> Features {
    // The office barcode and a box on its wall near it (the clutter may have put one there).
    let near = b.floors.last().is_some_and(|f| {
        let Some((_, _, bar)) = f.office else { return false };
        let horizontal = bar.facing.abs() == 90;
        f.obstacles.iter().any(|(_, lo, hi)| {
            let (a0, a1, n0, n1, p, q) = if horizontal {
                (lo.0, hi.0, lo.1, hi.1, bar.at.0, bar.at.1)
            } else {
                (lo.1, hi.1, lo.0, hi.0, bar.at.1, bar.at.0)
            };
            // On the barcode's wall (the box's face within 2 cm of the barcode's line), near it.
            let on_wall = (n0 - q).abs() <= 2 || (n1 - q).abs() <= 2;
            on_wall && (a0 - p).max(p - a1).max(0) <= NEAR_BARCODE
        })
    });
    Features {
        lobby: "facing",
        // Numbered in the order their walls were drawn: the button's wall (north), or a side.
        car_walls: walls_of.iter().map(|&w| if w == 'N' { "same" } else { "side" }).collect(),
        open_s: b.open_s,
        clutter_near_barcode: near,
        clutter_near_lab_barcode: false,
        corridor_band: "mixed",
        corridor_width: (
            widths.iter().copied().min().unwrap_or(0) as f64 / 100.0,
            widths.iter().copied().max().unwrap_or(0) as f64 / 100.0,
        ),
        junction_lobby: if stub { "+" } else { "T" },
        junction_goal: "T",
        junction_office: if side_corridor { "T" } else { "none" },
        junctions_passed: passed,
    }
}

pub(super) fn build(rng: &mut Rng, seed: u64, opts: &Options) -> Built {
    let mut widths = Vec::new();
    let nfloors = rng.int(opts.floors.0, opts.floors.1);
    let ncars = rng.int(opts.cars.0, opts.cars.1);
    let start_level = rng.int(-1, 0);
    let goal_level = start_level + nfloors - 1;
    let density = opts.clutter.unwrap_or_else(|| (rng.unit() * 30.0).round() / 100.0);
    let open_s = opts.open_s.unwrap_or_else(|| {
        let t = rng.unit();
        (((8.0 + 7.0 * t) * 10.0).round() / 10.0, ((12.0 + 13.0 * t) * 10.0).round() / 10.0)
    });
    let off = opts.barcode_offset;
    let off_hi = cm(off.1);

    // --- the lobby, in its own frame (south-west corner at 0, 0) ---
    let wb = rng.cm(opts.corridor_width); // the corridor into the lobby, and its entry
    widths.push(wb);
    let s = rng.int(180, 240);
    let (g, m) = (40, 30);
    let mut walls_of = vec!['N', 'N', 'E', 'W'];
    rng.shuffle(&mut walls_of);
    walls_of.truncate(ncars as usize);
    let kn = walls_of.iter().filter(|&&w| w == 'N').count();
    let stretch = 120.max(wb + 60);
    let items: Vec<bool> = match kn {
        0 => vec![false],
        1 if rng.coin() => vec![true, false],
        1 => vec![false, true],
        _ => vec![true, false, true],
    }; // true: a car
    let total: i64 =
        items.iter().map(|&c| if c { s } else { stretch }).sum::<i64>() + g * (items.len() as i64 - 1) + 2 * m;
    let lh = rng.int(400, 500);
    let lw = total.max(400) + rng.int(0, 60);
    let mut x = m + (lw - total) / 2;
    let mut cars_local: Vec<(char, CarB)> = Vec::new();
    let mut bx = 0;
    for &is_car in &items {
        if is_car {
            cars_local.push(('N', CarB { lo: (x, lh), hi: (x + s, lh + s), out: (0, -1), door: 0 }));
            x += s + g;
        } else {
            bx = x + stretch / 2;
            x += stretch + g;
        }
    }
    for &w in &walls_of {
        match w {
            'E' => cars_local.push(('E', CarB { lo: (lw, lh - m - s), hi: (lw + s, lh - m), out: (-1, 0), door: 0 })),
            'W' => cars_local.push(('W', CarB { lo: (-s, lh - m - s), hi: (0, lh - m), out: (1, 0), door: 0 })),
            _ => {}
        }
    }
    // Cars in the order their walls were drawn (north ones left to right).
    let mut order: Vec<CarB> = Vec::new();
    let mut north = cars_local.iter().filter(|(w, _)| *w == 'N').map(|(_, c)| *c);
    for &w in &walls_of {
        let c = match w {
            'N' => north.next(),
            o => cars_local.iter().find(|(x, _)| *x == o).map(|(_, c)| *c),
        };
        if let Some(mut c) = c {
            c.door = rng.cm(opts.door_width).min(s - 20);
            order.push(c);
        }
    }
    let lobby_walls = |f: &mut FloorB, ox: i64, oy: i64, open: bool| {
        let span = |w: char| -> Vec<(i64, i64)> {
            cars_local
                .iter()
                .filter(|(x, _)| *x == w)
                .map(|(_, c)| if w == 'N' { (ox + c.lo.0, ox + c.hi.0) } else { (oy + c.lo.1, oy + c.hi.1) })
                .collect()
        };
        f.hwall(oy + lh, ox, ox + lw, &span('N'));
        f.vwall(ox + lw, oy, oy + lh, &span('E'));
        f.vwall(ox, oy, oy + lh, &span('W'));
        let entry = if open { vec![(ox + bx - wb / 2, ox + bx - wb / 2 + wb)] } else { vec![] };
        f.hwall(oy, ox, ox + lw, &entry);
    };

    // --- the start floor (canonical: the corridor along x at y 0..w) ---
    let mut fs = FloorB { level: start_level, name: "start".into(), ..FloorB::default() };
    let w = rng.cm(opts.corridor_width);
    widths.push(w);
    let (lab_w, lab_h) = (rng.int(500, 900), rng.int(400, 700));
    let dw = rng.cm(opts.door_width);
    let lab_x0 = rng.int(off_hi + 50, lab_w - dw - off_hi - 50);
    fs.doors.push(hdoor(rng, "lab", 0, lab_x0, dw, off, 10, -90));
    fs.vwall(0, -lab_h, 0, &[]);
    fs.hwall(-lab_h, 0, lab_w, &[]);
    fs.vwall(lab_w, -lab_h, 0, &[]);
    // The start pose, clear of the door's approach.
    let start = (rng.int(100, lab_w - 100), rng.int(-lab_h + 100, -lab_h + 100 + (lab_h - 330).max(0)));
    let start_theta = 90 * rng.int(-1, 2);
    // Furniture against the lab's walls.
    let keep_out = [
        ((start.0 - 70, start.1 - 70), (start.0 + 70, start.1 + 70)),
        ((lab_x0 - off_hi - 90, -230), (lab_x0 + dw + off_hi + 90, 0)),
    ];
    let mut pieces: Vec<(Pt, Pt)> = Vec::new();
    let want = rng.int(2, 6);
    let names = ["desk", "table", "bench", "cabinet", "shelf", "robot parts"];
    for name in names.iter().take(want as usize) {
        for _ in 0..30 {
            let (a, d) = (rng.int(40, 160), rng.int(40, 90));
            let (lo, hi) = match rng.int(0, 3) {
                0 => {
                    let y = rng.int(-lab_h, -a);
                    ((0, y), (d, y + a))
                }
                1 => {
                    let y = rng.int(-lab_h, -a);
                    ((lab_w - d, y), (lab_w, y + a))
                }
                2 => {
                    let x = rng.int(0, lab_w - a);
                    ((x, -lab_h), (x + a, -lab_h + d))
                }
                _ => {
                    let x = rng.int(0, lab_w - a);
                    ((x, -d), (x + a, 0))
                }
            };
            let hits = |(p, q): &(Pt, Pt), gap: i64| {
                lo.0 < q.0 + gap && p.0 - gap < hi.0 && lo.1 < q.1 + gap && p.1 - gap < hi.1
            };
            if keep_out.iter().any(|r| hits(r, 0)) || pieces.iter().any(|r| hits(r, 75)) {
                continue;
            }
            pieces.push((lo, hi));
            fs.obstacles.push((name.to_string(), lo, hi));
            break;
        }
    }
    // The corridor: west end, the features, the junction to the lobby, the east end.
    let xw = -rng.int(0, 150);
    let nj = rng.int(opts.junctions.0, opts.junctions.1);
    let mut list = junction_list(rng, nj - 1);
    for _ in 0..rng.int(1, 3) {
        list.push(Feature::Room { north: rng.coin() });
    }
    rng.shuffle(&mut list);
    let mut passed = junction_kinds(&list);
    let (mut north_gaps, mut south_gaps) = (Vec::new(), vec![(lab_x0, lab_x0 + dw)]);
    let mut next_id = 11;
    let lb = rng.int(450, 650);
    let c0 = lab_w + rng.int(80, 200);
    let (jx, _, north_open) = features(
        rng,
        &mut fs,
        opts,
        &list,
        c0,
        (0, w),
        lb - 60,
        &mut next_id,
        &mut north_gaps,
        &mut south_gaps,
        &mut widths,
    );
    // The junction to the lobby: north (and a south stub: a + junction).
    north_gaps.push((jx, jx + wb));
    fs.vwall(jx, w, w + lb, &[]);
    fs.vwall(jx + wb, w, w + lb, &[]);
    let stub = rng.coin();
    if stub {
        let l = rng.int(200, 350);
        let ws = rng.cm(opts.corridor_width);
        widths.push(ws);
        let sx = jx + wb / 2 - ws / 2;
        fs.vwall(sx, -l, 0, &[]);
        fs.vwall(sx + ws, -l, 0, &[]);
        fs.hwall(-l, sx, sx + ws, &[]);
        south_gaps.push((sx, sx + ws));
    }
    let xe = jx + wb + rng.int(200, 400);
    fs.vwall(xw, 0, w, &[]);
    fs.vwall(xe, 0, w, &[]);
    fs.hwall(w, xw, xe, &north_gaps);
    fs.hwall(0, xw, xe, &south_gaps);
    // The lobby above the corridor, its entry on the junction's corridor.
    let (ox, oy) = (jx + wb / 2 - bx, w + lb);
    lobby_walls(&mut fs, ox, oy, true);
    let boff = rng.int(1, 2);
    let button = |id: i64| Bar { id, at: (ox + bx, oy + lh - boff), facing: -90 };
    fs.lobby = Some(button(30));
    let door_gaps_s: Vec<(i64, i64)> = fs.doors.iter().map(|d| (d.a.0, d.b.0)).collect();
    let mut boxes = Vec::new();
    let runs_s = [
        Run {
            horizontal: true,
            fixed: w,
            inward: -1,
            from: xw,
            to: xe,
            keep_clear: door_margins(&north_gaps, &door_gaps_s),
        },
        Run {
            horizontal: true,
            fixed: 0,
            inward: 1,
            from: xw,
            to: xe,
            keep_clear: door_margins(&south_gaps, &door_gaps_s),
        },
        Run { horizontal: false, fixed: jx, inward: 1, from: w, to: w + lb, keep_clear: vec![] },
        Run { horizontal: false, fixed: jx + wb, inward: -1, from: w, to: w + lb, keep_clear: vec![] },
    ];
    clutter(rng, &mut fs, &runs_s, density, &mut boxes);
    let lab_to_lobby = vec![
        turn("right"),
        junction_step("left", lab_x0 + dw / 2, jx, north_open + 1),
        Step(vec![("follow", "hallway".into()), ("until", "distance".into()), ("distance", metres(w / 2 + lb + 100))]),
        Step(vec![("home", "30".into())]),
    ];

    // --- the floors in between: the lobby, closed ---
    let mut floors = vec![fs];
    for k in 1..nfloors - 1 {
        let mut f = FloorB { level: start_level + k, ..FloorB::default() };
        lobby_walls(&mut f, ox, oy, false);
        f.lobby = Some(button(30 + k));
        floors.push(f);
    }

    // --- the goal floor: the lobby, a corridor south to a corridor along x ---
    let mut fg = FloorB { level: goal_level, name: "goal".into(), ..FloorB::default() };
    let goal_flip = rng.coin();
    let xc = jx + wb / 2; // the entry's centre line (mirror axis of the goal corridors)
    let w2 = rng.cm(opts.corridor_width);
    widths.push(w2);
    let lb2 = rng.int(350, 550);
    let y1 = oy - lb2;
    let y0 = y1 - w2;
    // Built in u = x - xc, mirrored at the end if goal_flip.
    let mut gf = FloorB::default();
    // u = x - xc: the entry is [-wb / 2, wb - wb / 2].
    gf.vwall(-wb / 2, y1, oy, &[]);
    gf.vwall(wb - wb / 2, y1, oy, &[]);
    let mut north_g = vec![(-wb / 2, wb - wb / 2)];
    let mut south_g: Vec<(i64, i64)> = Vec::new();
    let uw = -wb / 2 - rng.int(200, 400);
    let side_corridor = rng.coin();
    let njd = if side_corridor { rng.int(0, 1) } else { rng.int(1, 2) };
    let mut list = junction_list(rng, njd);
    for _ in 0..rng.int(0, 2) {
        list.push(Feature::Room { north: rng.coin() });
    }
    rng.shuffle(&mut list);
    passed.extend(junction_kinds(&list));
    let mut next_id = 41;
    let c0 = wb - wb / 2 + rng.int(150, 250);
    let (c, south_open, _) = features(
        rng,
        &mut gf,
        opts,
        &list,
        c0,
        (y0, y1),
        lb2 - 60,
        &mut next_id,
        &mut north_g,
        &mut south_g,
        &mut widths,
    );
    let mut runs_g = Vec::new();
    let mut button_to_office =
        vec![turn("back"), Step(vec![("follow", "hallway".into()), ("until", "wall".into()), ("turn", "left".into())])];
    let ue;
    if side_corridor {
        // The office on a corridor going south from a junction.
        let wc = rng.cm(opts.corridor_width);
        widths.push(wc);
        south_g.push((c, c + wc));
        let mut rooms = vec![true];
        if rng.coin() {
            rooms.push(false);
        }
        rng.shuffle(&mut rooms);
        let mut yb = y0 - rng.int(100, 200);
        let mut east_gaps = Vec::new();
        let mut door_gaps = Vec::new();
        let mut found = None;
        for is_office in rooms {
            let dwr = rng.cm(opts.door_width);
            let rh = (dwr + 2 * (off_hi + 50)).max(350) + rng.int(0, 100);
            let depth = rng.int(300, 450);
            let d0 = rng.int(yb - rh + off_hi + 40, yb - dwr - off_hi - 40);
            let id = if is_office { 40 } else { next_id };
            if !is_office {
                next_id += 1;
            }
            let door = vdoor(rng, if is_office { "office" } else { "room" }, c + wc, d0, dwr, off, id, 180);
            gf.hwall(yb, c + wc, c + wc + depth, &[]);
            gf.hwall(yb - rh, c + wc, c + wc + depth, &[]);
            gf.vwall(c + wc + depth, yb - rh, yb, &[]);
            east_gaps.push((d0, d0 + dwr));
            door_gaps.push((d0, d0 + dwr));
            if is_office {
                let bar = door.barcode.unwrap_or(Bar { id: 40, at: (0, 0), facing: 180 });
                gf.office = Some(((c + wc, yb - rh), (c + wc + depth, yb), bar));
                found = Some(DoorB { barcode: None, ..door.clone() });
            }
            gf.doors.push(DoorB { barcode: if is_office { None } else { door.barcode }, ..door });
            yb -= rh;
        }
        let yend = yb - rng.int(100, 250);
        gf.vwall(c, yend, y0, &[]);
        gf.vwall(c + wc, yend, y0, &east_gaps);
        gf.hwall(yend, c, c + wc, &[]);
        runs_g.push(Run { horizontal: false, fixed: c, inward: 1, from: yend, to: y0, keep_clear: vec![] });
        runs_g.push(Run {
            horizontal: false,
            fixed: c + wc,
            inward: -1,
            from: yend,
            to: y0,
            keep_clear: door_margins(&east_gaps, &door_gaps),
        });
        ue = c + wc + rng.int(200, 350);
        // From the T's middle (x 0), where `until: wall` stopped.
        button_to_office.push(junction_step("right", 0, c, south_open + 1));
        let d = found.unwrap_or_else(|| DoorB { name: String::new(), a: (0, 0), b: (0, 1), barcode: None });
        let bar = gf.office.map(|o| o.2);
        let full = DoorB { barcode: bar, ..d };
        button_to_office.extend(office_steps(&full));
    } else {
        // The office beside the corridor along x.
        let north = lb2 - 60 >= 300 && rng.coin();
        let dwr = rng.cm(opts.door_width);
        let ow = (dwr + 2 * (off_hi + 50)).max(350) + rng.int(0, 150);
        let od = rng.int(300, 420).min(if north { lb2 - 60 } else { 420 });
        let x0 = rng.int(c + off_hi + 40, c + ow - dwr - off_hi - 40);
        let (y, far, facing) = if north { (y1, y1 + od, -90) } else { (y0, y0 - od, 90) };
        let door = hdoor(rng, "office", y, x0, dwr, off, 40, facing);
        gf.vwall(c, y.min(far), y.max(far), &[]);
        gf.vwall(c + ow, y.min(far), y.max(far), &[]);
        gf.hwall(far, c, c + ow, &[]);
        if north {
            north_g.push((x0, x0 + dwr));
        } else {
            south_g.push((x0, x0 + dwr));
        }
        let bar = door.barcode.unwrap_or(Bar { id: 40, at: (0, 0), facing });
        gf.office = Some(((c, y.min(far)), (c + ow, y.max(far)), bar));
        gf.doors.push(DoorB { barcode: None, ..door.clone() });
        button_to_office.extend(office_steps(&door));
        ue = c + ow + rng.int(200, 350);
    }
    gf.vwall(uw, y0, y1, &[]);
    gf.vwall(ue, y0, y1, &[]);
    gf.hwall(y1, uw, ue, &north_g);
    gf.hwall(y0, uw, ue, &south_g);
    let all_doors: Vec<(i64, i64)> = gf.doors.iter().filter(|d| d.a.1 == d.b.1).map(|d| (d.a.0, d.b.0)).collect();
    // The wall facing the corridor from the lobby stays clear of doors and clutter.
    let mouth = (-wb / 2 - 60, wb - wb / 2 + 60);
    let mut south_keep = door_margins(&south_g, &all_doors);
    south_keep.push(mouth);
    runs_g.push(Run {
        horizontal: true,
        fixed: y1,
        inward: -1,
        from: uw,
        to: ue,
        keep_clear: door_margins(&north_g, &all_doors),
    });
    runs_g.push(Run { horizontal: true, fixed: y0, inward: 1, from: uw, to: ue, keep_clear: south_keep });
    runs_g.push(Run { horizontal: false, fixed: -wb / 2, inward: 1, from: y1, to: oy, keep_clear: vec![] });
    runs_g.push(Run { horizontal: false, fixed: wb - wb / 2, inward: -1, from: y1, to: oy, keep_clear: vec![] });
    let mut boxes = Vec::new();
    clutter(rng, &mut gf, &runs_g, density, &mut boxes);
    // Into the building's frame: x = xc ± u.
    // Mirrored about the entry's centre: its ends swap exactly.
    let (e0, e1) = (xc - wb / 2, xc - wb / 2 + wb);
    let map_x = |u: i64| if goal_flip { e0 + e1 - xc - u } else { xc + u };
    let mp = |p: Pt| (map_x(p.0), p.1);
    let mf = |a: i64| if goal_flip { norm_deg(180 - a) } else { a };
    for (a, b) in gf.walls {
        fg.walls.push((mp(a), mp(b)));
    }
    for (n, a, b) in gf.obstacles {
        let (p, q) = (mp(a), mp(b));
        fg.obstacles.push((n, (p.0.min(q.0), p.1), (p.0.max(q.0), q.1)));
    }
    let mbar = |b: Bar| Bar { id: b.id, at: mp(b.at), facing: mf(b.facing) };
    for d in gf.doors {
        fg.doors.push(DoorB { name: d.name, a: mp(d.a), b: mp(d.b), barcode: d.barcode.map(mbar) });
    }
    if let Some((a, b, bar)) = gf.office {
        let (p, q) = (mp(a), mp(b));
        fg.office = Some(((p.0.min(q.0), p.1), (p.0.max(q.0), q.1), mbar(bar)));
    }
    lobby_walls(&mut fg, ox, oy, true);
    fg.lobby = Some(button(30 + nfloors - 1));
    if goal_flip {
        for st in &mut button_to_office {
            for (_, v) in &mut st.0 {
                *v = flip_word(v);
            }
        }
    }
    floors.push(fg);

    let cars: Vec<CarB> =
        order.iter().map(|c| CarB { lo: (c.lo.0 + ox, c.lo.1 + oy), hi: (c.hi.0 + ox, c.hi.1 + oy), ..*c }).collect();
    let mut b = Building {
        floors,
        cars,
        start: (start.0, start.1, start_theta),
        start_level,
        goal_level,
        open_s,
        lab_to_lobby,
        button_to_office,
    };
    let _ = seed;
    b.transform(rng.coin(), rng.int(0, 3));
    let features = features_of(&b, &walls_of, &widths, (stub, side_corridor), passed);
    Built { building: b, corridor_widths: widths, junctions: nj as usize, clutter: density, features }
}
