//! push_button and say.

use situate_robot::{Arm, Target};
use situate_skills::{PushButton, Say};

use crate::harness::{val, Harness};

fn press(h: &mut Harness, t: Target, arm: Option<Arm>) -> Option<i64> {
    let mut inputs = vec![("target", val(t))];
    if let Some(a) = arm {
        inputs.push(("arm", val(a)));
    }
    h.run(&inputs).get::<i64>("press")
}

#[test]
fn push_button_presses_only_in_reach_and_retries_until_a_hit() {
    let mut h = Harness::new::<PushButton>().param("button", val(3i64)).param("retry_s", val(1.0));
    let arm = |presses| Some(Arm { attempts: 0, presses });
    let far = Target { seen: true, id: 5, bearing: 0.0, distance: 1.0 };
    let aside = Target { distance: 0.5, bearing: 0.7, ..far };
    let unseen = Target { seen: false, distance: 0.5, ..far };
    let near = Target { distance: 0.5, bearing: 0.1, ..far };
    for t in [far, aside, unseen] {
        assert_eq!(press(&mut h, t, arm(0)), None, "out of reach: {t:?}");
    }
    assert_eq!(press(&mut h, near, arm(0)), Some(3));
    // The harness runs 20 cycles a second: no retry before 1 s.
    for _ in 0..19 {
        assert_eq!(press(&mut h, near, arm(0)), None);
    }
    assert_eq!(press(&mut h, near, arm(0)), Some(3), "retried after retry_s");
    assert_eq!(press(&mut h, near, arm(1)), None, "hit: done");
    for _ in 0..40 {
        assert_eq!(press(&mut h, near, arm(1)), None, "done until re-activated");
    }
    h.skip(5);
    assert_eq!(press(&mut h, near, arm(1)), Some(3), "re-activated: pushes again");
}

#[test]
fn say_speaks_once_per_activation_and_on_a_new_message() {
    let mut h = Harness::new::<Say>().param("message", val("going up".to_string()));
    let say = |h: &mut Harness| h.run(&[]).get::<String>("say");
    assert_eq!(say(&mut h).as_deref(), Some("going up"));
    assert_eq!(say(&mut h), None);
    assert_eq!(say(&mut h), None);
    h.skip(3);
    assert_eq!(say(&mut h).as_deref(), Some("going up"), "again after re-activation");
    h.set("message", val("arrived".to_string()));
    assert_eq!(say(&mut h).as_deref(), Some("arrived"));
    assert_eq!(say(&mut h), None);
}
