use super::*;

fn square(cx: f64, cy: f64, side: f64) -> Roi {
    Roi {
        center_x_px: cx,
        center_y_px: cy,
        width_px: side,
        height_px: side,
        rotation_rad: 0.0,
    }
}

/// A scripted world: people at positions per frame (what the detector
/// finds and the landmark model sees) and "clutter" where the landmark
/// model sees a pose but the detector finds nobody.
struct World {
    people: Vec<[f64; 2]>,
    clutter: Vec<[f64; 2]>,
    /// Where a crop of the landmark model goes next: the nearest person
    /// or clutter within half a side of its centre.
    side: f64,
    detector_blind: bool,
}

impl Sensors for World {
    type Pose = [f64; 2];
    fn landmarks(&mut self, roi: &Roi, _: &mut PointsFilter) -> Result<Option<Seen<[f64; 2]>>> {
        let near = self
            .people
            .iter()
            .chain(self.clutter.iter())
            .map(|p| {
                (
                    ((p[0] - roi.center_x_px).powi(2) + (p[1] - roi.center_y_px).powi(2)).sqrt(),
                    *p,
                )
            })
            .filter(|(d, _)| *d < self.side / 2.0)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        Ok(near.map(|(_, p)| Seen {
            pose: p,
            next_roi: Some(square(p[0], p[1], self.side)),
        }))
    }
    fn detect(&mut self, region: &Roi) -> Result<Vec<Candidate>> {
        if self.detector_blind {
            return Ok(Vec::new());
        }
        let b = roi_box(region);
        Ok(self
            .people
            .iter()
            .filter(|p| p[0] >= b[0] && p[0] < b[2] && p[1] >= b[1] && p[1] < b[3])
            .map(|p| Candidate {
                score: 0.9,
                roi: square(p[0], p[1], self.side),
            })
            .collect())
    }
}

fn tracker(params: PeopleParams) -> Tracker {
    let tiles = vec![Roi::letterbox(1000, 500)];
    Tracker::new(params, OneEuroParams::AUX_LANDMARKS, tiles).unwrap()
}

fn ids(r: &FrameResult<[f64; 2]>) -> Vec<(PersonId, [f64; 2])> {
    let mut v: Vec<_> = r
        .poses
        .iter()
        .filter_map(|p| p.id.map(|id| (id, p.pose)))
        .collect();
    v.sort_by_key(|x| x.0);
    v
}

#[test]
fn two_people_get_two_steady_ids() {
    let mut tr = tracker(PeopleParams::default());
    let mut w = World {
        people: vec![[200.0, 250.0], [700.0, 250.0]],
        clutter: vec![],
        side: 200.0,
        detector_blind: false,
    };
    let mut last = Vec::new();
    for k in 0..300 {
        let t = k as f64 / 30.0;
        // Both sway a little.
        w.people[0][0] = 200.0 + 20.0 * (t * 3.0).sin();
        w.people[1][1] = 250.0 + 20.0 * (t * 2.0).cos();
        let r = tr.step(t, &mut w).unwrap();
        if k >= 3 {
            last = ids(&r);
            assert_eq!(last.len(), 2, "frame {k}: {r:?}");
        }
    }
    assert_eq!(last[0].0, 1);
    assert_eq!(last[1].0, 2);
    assert!(last[0].1[0] < 400.0 && last[1].1[0] > 400.0);
}

#[test]
fn a_crop_left_on_clutter_is_dropped_within_the_confirmation_time() {
    let mut tr = tracker(PeopleParams::default());
    // A person walks past a lamp post; the crop sticks to the post.
    let mut w = World {
        people: vec![[300.0, 250.0]],
        clutter: vec![],
        side: 200.0,
        detector_blind: false,
    };
    for k in 0..30 {
        tr.step(k as f64 / 30.0, &mut w).unwrap();
    }
    // The person vanishes; clutter sits where they stood.
    w.people.clear();
    w.clutter.push([305.0, 250.0]);
    let mut dropped = None;
    let mut last_pose_frame = 0;
    for k in 30..120 {
        let r = tr.step(k as f64 / 30.0, &mut w).unwrap();
        if !r.poses.is_empty() {
            last_pose_frame = k;
        }
        for e in &r.events {
            if let TrackEvent::Dropped { keep_until, .. } = e {
                dropped = Some((k, *keep_until));
            }
        }
    }
    let (at, keep_until) = dropped.expect("the crop on the post is dropped");
    // Dropped one second (30 frames) after the last detection, which was
    // on frame 29 or before, and those frames are taken back.
    assert!(at <= 29 + 31, "dropped at {at}");
    assert!(keep_until <= 29);
    assert!(last_pose_frame < at);
}

#[test]
fn an_occluded_person_comes_back_with_the_same_id() {
    let mut tr = tracker(PeopleParams::default());
    let mut w = World {
        people: vec![[200.0, 250.0], [700.0, 250.0]],
        clutter: vec![],
        side: 200.0,
        detector_blind: false,
    };
    for k in 0..30 {
        tr.step(k as f64 / 30.0, &mut w).unwrap();
    }
    // The second person is hidden for half a second, then reappears a little further on.
    let hidden = w.people.pop().unwrap();
    for k in 30..45 {
        let r = tr.step(k as f64 / 30.0, &mut w).unwrap();
        assert_eq!(ids(&r).len(), 1);
    }
    w.people.push([hidden[0] + 30.0, hidden[1]]);
    let mut back = Vec::new();
    for k in 45..90 {
        back = ids(&tr.step(k as f64 / 30.0, &mut w).unwrap());
    }
    assert_eq!(back.iter().map(|x| x.0).collect::<Vec<_>>(), vec![1, 2]);
}

#[test]
fn crossing_people_keep_their_ids() {
    let mut tr = tracker(PeopleParams::default());
    let mut w = World {
        people: vec![[100.0, 250.0], [900.0, 250.0]],
        clutter: vec![],
        side: 150.0,
        detector_blind: false,
    };
    // They walk towards each other at 200 px/s, pass, and walk on.
    let mut last = Vec::new();
    for k in 0..120 {
        let t = k as f64 / 30.0;
        w.people[0][0] = 100.0 + 200.0 * t;
        w.people[1][0] = 900.0 - 200.0 * t;
        // While passing they stand in each other's way: one is hidden.
        let dist = (w.people[0][0] - w.people[1][0]).abs();
        let saved = w.people.clone();
        if dist < 60.0 {
            w.people.truncate(1);
        }
        let r = tr.step(t, &mut w).unwrap();
        w.people = saved;
        last = ids(&r);
    }
    // Person 1 started on the left and is now on the right.
    assert_eq!(last.len(), 2, "{last:?}");
    let p1 = last.iter().find(|x| x.0 == 1).unwrap().1;
    let p2 = last.iter().find(|x| x.0 == 2).unwrap().1;
    assert!(p1[0] > p2[0], "ids swapped: {last:?}");
}

#[test]
fn more_people_than_allowed_are_refused_and_counted() {
    let mut tr = tracker(PeopleParams {
        max_people: 3,
        ..Default::default()
    });
    let mut w = World {
        people: (0..6).map(|k| [80.0 + 160.0 * k as f64, 250.0]).collect(),
        clutter: vec![],
        side: 100.0,
        detector_blind: false,
    };
    let mut r = None;
    for k in 0..20 {
        r = Some(tr.step(k as f64 / 30.0, &mut w).unwrap());
    }
    assert_eq!(ids(&r.unwrap()).len(), 3);
    let (refused, first) = tr.refused();
    assert!(refused > 0);
    assert_eq!(first, Some(0));
    assert_eq!(tr.most_seen(), 6);
}

#[test]
fn nobody_in_view_gives_no_pose_and_no_track() {
    let mut tr = tracker(PeopleParams::default());
    let mut w = World {
        people: vec![],
        clutter: vec![[100.0, 100.0]],
        side: 100.0,
        detector_blind: true,
    };
    for k in 0..60 {
        let r = tr.step(k as f64 / 30.0, &mut w).unwrap();
        assert!(r.poses.is_empty());
    }
}

#[test]
fn params_are_checked() {
    assert!(PeopleParams::default().validate().is_ok());
    for bad in [
        PeopleParams {
            max_people: 0,
            ..Default::default()
        },
        PeopleParams {
            confirm_s: f64::NAN,
            ..Default::default()
        },
        PeopleParams {
            recheck_s: 2.0,
            ..Default::default()
        },
        PeopleParams {
            tile_overlap: 1.0,
            ..Default::default()
        },
        PeopleParams {
            tile_sides: vec![0.0],
            ..Default::default()
        },
        PeopleParams {
            birth_frames: 0,
            ..Default::default()
        },
    ] {
        assert!(bad.validate().is_err(), "{bad:?}");
    }
}

#[test]
fn assignment_maximises_overlap_and_respects_the_minimum() {
    let s = [[0.9, 0.8], [0.85, 0.1]];
    let p = assign(2, 2, |i, j| s[i][j], 0.3);
    let mut p = p;
    p.sort();
    assert_eq!(p, vec![(0, 1), (1, 0)]);
    // More rows than columns; a pair below the minimum is not kept.
    let s = [[0.2], [0.5], [0.9]];
    assert_eq!(assign(3, 1, |i, j| s[i][j], 0.3), vec![(2, 0)]);
    assert!(assign(1, 1, |_, _| 0.1, 0.3).is_empty());
}
