//! The generator's second family of buildings (`--family 2`, the default):
//! draws from the whole space `docs/maps.md` allows (lobby kinds, car walls,
//! open times, corridor bands, the junctions to the lobby, the goal corridor
//! and the office), laid out in the canonical frame.

use super::corridor::{
    box_beside, clutter, door_margins, features, hdoor, junction_kinds, junction_list, vdoor, Feature, Run,
};
use super::route::{flip_word, junction_step, office_steps, turn};
use super::{
    cm, lobby, metres, norm_deg, Bar, Building, Built, CarB, DoorB, Features, FloorB, Options, Pt, Rng, Step,
    NEAR_BARCODE,
};
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

/// The seed of the lab bin's own stream is the building's, xor this.
const LAB_BIN_STREAM: u64 = 0x6c61_625f_6269_6e73;

pub(super) fn build(rng: &mut Rng, seed: u64, opts: &Options) -> Built {
    let mut widths = Vec::new();
    let nfloors = rng.int(opts.floors.0, opts.floors.1);
    let ncars = rng.int(opts.cars.0, opts.cars.1);
    let start_level = rng.int(-1, 0);
    let goal_level = start_level + nfloors - 1;
    let density = opts.clutter.unwrap_or_else(|| (rng.unit() * 30.0).round() / 100.0);
    // The shortest open times the docs allow ([8, 12]) in one building of four, the others
    // anywhere from there to [15, 25].
    let open_s = opts.open_s.unwrap_or_else(|| {
        let t = if rng.int(0, 3) == 0 { 0.0 } else { rng.unit() };
        (((8.0 + 7.0 * t) * 10.0).round() / 10.0, ((12.0 + 13.0 * t) * 10.0).round() / 10.0)
    });
    // Corridor widths: in half the buildings each drawn over the whole range, in the others
    // all from its lower, middle or upper third (every corridor narrow, or every one wide).
    let corridor_band;
    let opts = &{
        let (lo, hi) = opts.corridor_width;
        let third = (hi - lo) / 3.0;
        let (name, band) = match rng.int(0, 5) {
            0 => ("narrow", (lo, lo + third)),
            1 => ("middle", (lo + third, hi - third)),
            2 => ("wide", (hi - third, hi)),
            _ => ("mixed", (lo, hi)),
        };
        corridor_band = name;
        Options { corridor_width: ((band.0 * 100.0).round() / 100.0, (band.1 * 100.0).round() / 100.0), ..opts.clone() }
    };
    let off = opts.barcode_offset;
    let off_hi = cm(off.1);

    // --- the lobby, in its own frame (south-west corner at 0, 0) ---
    let wb = rng.cm(opts.corridor_width); // the corridor into the lobby, and its entry
    widths.push(wb);
    let boff = rng.int(1, 2);
    let lobby = lobby::layout(rng, ncars as usize, wb, opts.door_width, boff);
    let ex = lobby.entry.0 + wb / 2; // the entry's centre (x, lobby frame), as the corridor's

    // --- the start floor (canonical: the corridor along x at y 0..w) ---
    let mut fs = FloorB { level: start_level, name: "start".into(), ..FloorB::default() };
    let w = rng.cm(opts.corridor_width);
    widths.push(w);
    let (lab_w, lab_h) = (rng.int(500, 900), rng.int(400, 700));
    let dw = rng.cm(opts.door_width);
    let lab_x0 = rng.int(off_hi + 50, lab_w - dw - off_hi - 50);
    let lab_door = hdoor(rng, "lab", 0, lab_x0, dw, off, 10, -90);
    let lab_bar = lab_door.barcode;
    fs.doors.push(lab_door);
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
    // In a third of the buildings a bin beside the lab door's barcode, on its wall (the far side
    // from the door; docs/maps.md allows furniture there, and seen aslant it pulls the scan's
    // best line off the wall). Drawn from a stream of its own: the rest of the building is the
    // one drawn without it.
    let mut own = Rng(ChaCha8Rng::seed_from_u64(seed ^ LAB_BIN_STREAM));
    let clutter_near_lab_barcode = match lab_bar {
        Some(bar) if own.int(0, 2) == 0 => {
            let near = (true, 0, -1, bar.at.0, (lab_x0, lab_x0 + dw), (0, lab_w));
            let placed = box_beside(&mut own, &mut fs, near, &mut Vec::new());
            if let Some(last) = fs.obstacles.last_mut().filter(|_| placed) {
                last.0 = "bin".to_string();
            }
            placed
        }
        _ => false,
    };
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
    // The junction to the lobby, north: a T (the corridor goes on to a dead end), a + (and a
    // stub south) or an L (the corridor ends there).
    let junction_lobby = ["T", "+", "L"][rng.int(0, 2) as usize];
    north_gaps.push((jx, jx + wb));
    fs.vwall(jx, w, w + lb, &[]);
    fs.vwall(jx + wb, w, w + lb, &[]);
    if junction_lobby == "+" {
        let l = rng.int(200, 350);
        let ws = rng.cm(opts.corridor_width);
        widths.push(ws);
        let sx = jx + wb / 2 - ws / 2;
        fs.vwall(sx, -l, 0, &[]);
        fs.vwall(sx + ws, -l, 0, &[]);
        fs.hwall(-l, sx, sx + ws, &[]);
        south_gaps.push((sx, sx + ws));
    }
    let xe = if junction_lobby == "L" { jx + wb } else { jx + wb + rng.int(200, 400) };
    fs.vwall(xw, 0, w, &[]);
    fs.vwall(xe, 0, w, &[]);
    fs.hwall(w, xw, xe, &north_gaps);
    fs.hwall(0, xw, xe, &south_gaps);
    // The lobby above the corridor, its entry on the junction's corridor.
    let (ox, oy) = (jx + wb / 2 - ex, w + lb);
    lobby::walls(&lobby, &mut fs, (ox, oy), true);
    let button = |id: i64| Bar { id, at: (ox + lobby.button.at.0, oy + lobby.button.at.1), ..lobby.button };
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
    // At an L the corridor's end wall says where to turn; at a T or a + the junction.
    let to_lobby = if junction_lobby == "L" {
        Step(vec![("follow", "hallway".into()), ("until", "wall".into()), ("turn", "left".into())])
    } else {
        junction_step("left", lab_x0 + dw / 2, jx, north_open + 1)
    };
    let mut lab_to_lobby = vec![
        turn("right"),
        to_lobby,
        Step(vec![
            ("follow", "hallway".into()),
            ("until", "distance".into()),
            ("distance", metres(w / 2 + lb + lobby.inside)),
        ]),
    ];
    lab_to_lobby.extend(lobby.turn_in.map(turn));
    lab_to_lobby.push(Step(vec![("home", "30".into())]));

    // --- the floors in between: the lobby, closed ---
    let mut floors = vec![fs];
    for k in 1..nfloors - 1 {
        let mut f = FloorB { level: start_level + k, ..FloorB::default() };
        lobby::walls(&lobby, &mut f, (ox, oy), false);
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
    // The lobby's corridor ends in a T (a dead end the other way) or an L.
    let junction_goal = if rng.coin() { "T" } else { "L" };
    let uw = if junction_goal == "L" { -wb / 2 } else { -wb / 2 - rng.int(200, 400) };
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
    // The steps after the lobby's (mirrored with the goal corridors).
    let mut button_to_office =
        vec![Step(vec![("follow", "hallway".into()), ("until", "wall".into()), ("turn", "left".into())])];
    let ue;
    // Where a box may stand beside the office barcode, on its wall: along which wall (horizontal,
    // fixed, inward), the barcode's and the door's places along it and the office's stretch.
    let near_barcode: (bool, i64, i64, i64, (i64, i64), (i64, i64));
    let junction_office;
    if side_corridor {
        // The office on a corridor going south from a junction: a T (the corridor along x goes on
        // to a dead end), a + (and a stub north) or an L (it ends there).
        junction_office = ["T", "+", "L"][rng.int(0, 2) as usize];
        let wc = rng.cm(opts.corridor_width);
        widths.push(wc);
        south_g.push((c, c + wc));
        if junction_office == "+" {
            let l = rng.int(200, 350).min(lb2 - 60);
            gf.vwall(c, y1, y1 + l, &[]);
            gf.vwall(c + wc, y1, y1 + l, &[]);
            gf.hwall(y1 + l, c, c + wc, &[]);
            north_g.push((c, c + wc));
        }
        let mut rooms = vec![true];
        if rng.coin() {
            rooms.push(false);
        }
        rng.shuffle(&mut rooms);
        let mut yb = y0 - rng.int(100, 200);
        let mut east_gaps = Vec::new();
        let mut door_gaps = Vec::new();
        let mut found = None;
        let mut near = None;
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
                near = Some((false, c + wc, -1, bar.at.1, (d0, d0 + dwr), (yb - rh, yb)));
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
        near_barcode = near.unwrap_or((false, 0, 1, 0, (0, 0), (0, 0)));
        if junction_office == "L" {
            ue = c + wc;
            button_to_office.push(Step(vec![
                ("follow", "hallway".into()),
                ("until", "wall".into()),
                ("turn", "right".into()),
            ]));
        } else {
            ue = c + wc + rng.int(200, 350);
            // From the T's middle (x 0), where `until: wall` stopped.
            button_to_office.push(junction_step("right", 0, c, south_open + 1));
        }
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
        junction_office = "none";
        near_barcode = (true, y, if north { -1 } else { 1 }, bar.at.0, (x0, x0 + dwr), (c, c + ow));
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
    // In half the buildings a box beside the office barcode, on its wall (the far side from the
    // door), laid first: the other clutter keeps its distances from it.
    let mut boxes = Vec::new();
    if rng.coin() {
        box_beside(rng, &mut gf, near_barcode, &mut boxes);
    }
    clutter(rng, &mut gf, &runs_g, density, &mut boxes);
    let (nh, nfixed, _, np, _, _) = near_barcode;
    let clutter_near_barcode = boxes.iter().any(|&(lo, hi, wall)| {
        let (a, b) = if nh { (lo.0, hi.0) } else { (lo.1, hi.1) };
        wall == (nh, nfixed) && (a - np).max(np - b).max(0) <= NEAR_BARCODE
    });
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
    lobby::walls(&lobby, &mut fg, (ox, oy), true);
    fg.lobby = Some(button(30 + nfloors - 1));
    if goal_flip {
        for st in &mut button_to_office {
            for (_, v) in &mut st.0 {
                *v = flip_word(v);
            }
        }
    }
    // From facing the button: towards the entry (the lobby is not mirrored with the corridors).
    button_to_office.insert(0, turn(lobby.turn_out));
    floors.push(fg);

    let cars: Vec<CarB> = lobby
        .cars
        .iter()
        .map(|(_, c)| CarB { lo: (c.lo.0 + ox, c.lo.1 + oy), hi: (c.hi.0 + ox, c.hi.1 + oy), ..*c })
        .collect();
    let features = Features {
        lobby: lobby.kind,
        car_walls: lobby.relations.clone(),
        open_s,
        clutter_near_barcode,
        clutter_near_lab_barcode,
        corridor_band,
        corridor_width: (
            widths.iter().copied().min().unwrap_or(0) as f64 / 100.0,
            widths.iter().copied().max().unwrap_or(0) as f64 / 100.0,
        ),
        junction_lobby,
        junction_goal,
        junction_office,
        junctions_passed: passed,
    };
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
    Built { building: b, corridor_widths: widths, junctions: nj as usize, clutter: density, features }
}
