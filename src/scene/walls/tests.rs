//! Tests of wall extraction ([`super`]): the rectangle a face gives (under its lower top, above
//! its higher bottom), walls joined across triangulations and splits, gables and steps, holes,
//! leaning and non-planar faces refused, duplicated faces, closed boxes, and the exact check
//! that refuses a rectangle an edge enters.
//!
//! Input: small meshes built here. Output: pass or fail.
//! Invariant: every expected wall is stated by hand from the faces it comes from.

use super::*;
use crate::scene::Face;

/// A mesh from vertex triples and faces given as outer rings (vertex indices).
fn mesh(vs: &[[f64; 3]], faces: &[&[u32]]) -> Mesh {
    Mesh {
        vertices: vs.iter().map(|v| DVec3::from_array(*v)).collect(),
        faces: faces
            .iter()
            .map(|f| Face {
                rings: vec![f.to_vec()],
            })
            .collect(),
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 2e-9
}

#[test]
fn one_quad_gives_its_rectangle_under_the_lower_top_above_the_higher_bottom() {
    // Bottom from (0,0,0) to (10,0,1), top from (10,0,12) to (0,0,10).
    let m = mesh(
        &[[0., 0., 0.], [10., 0., 1.], [10., 0., 12.], [0., 0., 10.]],
        &[&[0, 1, 2, 3]],
    );
    let w = wall_pieces(&m);
    assert_eq!(w.len(), 1, "{w:?}");
    let w = w[0];
    assert_eq!((w.a, w.b), (DVec2::new(0., 0.), DVec2::new(10., 0.)));
    assert!(w.base > 1.0 && close(w.base, 1.0), "{w:?}");
    assert!(w.top < 10.0 && close(w.top, 10.0), "{w:?}");
}

#[test]
fn a_triangulated_wall_and_a_wall_split_side_by_side_give_one_long_wall() {
    // A 4 m high wall from x = 0 to x = 20 at y = 5, as two triangles on [0, 8] and a quad
    // on [8, 20]: the triangles' diagonal cancels, the two parts join at x = 8.
    let m = mesh(
        &[
            [0., 5., 0.],
            [8., 5., 0.],
            [8., 5., 4.],
            [0., 5., 4.],
            [20., 5., 0.],
            [20., 5., 4.],
        ],
        &[&[0, 1, 2], &[0, 2, 3], &[1, 4, 5, 2]],
    );
    let w = wall_pieces(&m);
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!((w[0].a, w[0].b), (DVec2::new(0., 5.), DVec2::new(20., 5.)));
    assert!(close(w[0].base, 0.0) && close(w[0].top, 4.0), "{w:?}");
}

#[test]
fn a_gable_wall_gives_the_rectangle_to_the_eaves_and_a_stepped_one_its_tall_part() {
    // Gable: eaves at 6 m, ridge at 9 m in the middle.
    let m = mesh(
        &[
            [0., 0., 0.],
            [10., 0., 0.],
            [10., 0., 6.],
            [5., 0., 9.],
            [0., 0., 6.],
        ],
        &[&[0, 1, 2, 3, 4]],
    );
    let w = wall_pieces(&m);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(close(w[0].top, 6.0) && close(w[0].base, 0.0), "{w:?}");
    // Stepped: 5 m high from x = 0 to 4, 12 m from 4 to 6, 5 m from 6 to 10.
    let m = mesh(
        &[
            [0., 0., 0.],
            [10., 0., 0.],
            [10., 0., 5.],
            [6., 0., 5.],
            [6., 0., 12.],
            [4., 0., 12.],
            [4., 0., 5.],
            [0., 0., 5.],
        ],
        &[&[0, 1, 2, 3, 4, 5, 6, 7]],
    );
    let mut w = wall_pieces(&m);
    w.sort_by(|a, b| a.top.total_cmp(&b.top));
    assert_eq!(w.len(), 2, "{w:?}");
    assert_eq!((w[0].a.x, w[0].b.x), (0.0, 10.0));
    assert!(close(w[0].top, 5.0));
    assert_eq!((w[1].a.x, w[1].b.x), (4.0, 6.0));
    assert!(close(w[1].top, 12.0));
}

#[test]
fn a_window_hole_splits_the_wall() {
    // A 10 x 6 wall with a window from x = 4 to 6, z = 2 to 4.
    let mut m = mesh(
        &[
            [0., 0., 0.],
            [10., 0., 0.],
            [10., 0., 6.],
            [0., 0., 6.],
            [4., 0., 2.],
            [6., 0., 2.],
            [6., 0., 4.],
            [4., 0., 4.],
        ],
        &[&[0, 1, 2, 3]],
    );
    m.faces[0].rings.push(vec![4, 7, 6, 5]);
    let w = wall_pieces(&m);
    assert!(!w.is_empty());
    for p in &w {
        // No piece spans the window: over x in [4, 6] it stays below 2 or above 4.
        let spans = p.a.x.min(p.b.x) < 6.0 && p.a.x.max(p.b.x) > 4.0;
        assert!(!spans || p.top <= 2.0 || p.base >= 4.0, "{p:?}");
    }
    // The full-height parts beside the window are there.
    assert!(w
        .iter()
        .any(|p| p.a.x.max(p.b.x) <= 4.0 && close(p.top, 6.0)));
    assert!(w
        .iter()
        .any(|p| p.a.x.min(p.b.x) >= 6.0 && close(p.top, 6.0)));
}

#[test]
fn leaning_roofs_and_faces_off_their_plane_give_nothing() {
    // A wall whose top edge is 1 mm off the bottom's vertical plane, a roof, and a
    // quad whose fourth vertex strays 0.1 mm from the others' plane.
    let m = mesh(
        &[
            [0., 0., 0.],
            [10., 0., 0.],
            [10., 0.001, 6.],
            [0., 0.001, 6.],
            [0., 0., 6.],
            [10., 0., 6.],
            [10., 5., 9.],
            [0., 5., 9.],
            [0., 10., 0.],
            [10., 10., 0.],
            [10., 10., 6.],
            [0., 10.0001, 6.],
        ],
        &[&[0, 1, 2, 3], &[4, 5, 6, 7], &[8, 9, 10, 11]],
    );
    assert!(wall_pieces(&m).is_empty());
}

#[test]
fn duplicated_and_overlapping_faces_still_give_their_union() {
    // The same quad twice (once reversed), and a taller quad over it sharing no edge: the
    // union is 0..9 m high, though the even-odd sum of all three would have holes.
    let m = mesh(
        &[
            [0., 0., 0.],
            [10., 0., 0.],
            [10., 0., 8.],
            [0., 0., 8.],
            [0., 0., 3.],
            [10., 0., 3.],
            [10., 0., 9.],
            [0., 0., 9.],
        ],
        &[&[0, 1, 2, 3], &[3, 2, 1, 0], &[4, 5, 6, 7]],
    );
    let w = wall_pieces(&m);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(close(w[0].base, 0.0) && close(w[0].top, 9.0), "{w:?}");
}

#[test]
fn a_closed_box_gains_its_four_walls() {
    let m = mesh(
        &[
            [0., 0., 0.],
            [4., 0., 0.],
            [4., 3., 0.],
            [0., 3., 0.],
            [0., 0., 5.],
            [4., 0., 5.],
            [4., 3., 5.],
            [0., 3., 5.],
        ],
        &[
            &[0, 3, 2, 1],
            &[4, 5, 6, 7],
            &[0, 1, 5, 4],
            &[1, 2, 6, 5],
            &[2, 3, 7, 6],
            &[3, 0, 4, 7],
        ],
    );
    let w = wall_pieces(&m);
    assert_eq!(w.len(), 4, "{w:?}");
    assert!(w.iter().all(|p| close(p.base, 0.0) && close(p.top, 5.0)));
}
#[test]
fn the_exact_check_refuses_rectangles_that_an_edge_enters() {
    let v = DVec2::new;
    let ring = |pts: &[DVec2]| -> Vec<[DVec2; 2]> {
        (0..pts.len())
            .map(|i| [pts[i], pts[(i + 1) % pts.len()]])
            .collect()
    };
    // A 10 x 6 face with a hole from (4,2) to (6,4), in (u, z).
    let mut e = ring(&[v(0., 0.), v(10., 0.), v(10., 6.), v(0., 6.)]);
    e.extend(ring(&[v(4., 2.), v(4., 4.), v(6., 4.), v(6., 2.)]));
    assert!(
        rect_in_region(&e, 0.0, 10.0, 0.0, 2.0),
        "touching the hole's bottom"
    );
    assert!(rect_in_region(&e, 0.0, 4.0, 0.0, 6.0), "touching its side");
    assert!(!rect_in_region(&e, 0.0, 10.0, 0.0, 2.5), "into the hole");
    assert!(
        !rect_in_region(&e, 1.0, 9.0, 1.0, 5.0),
        "around the hole (centre in it)"
    );
    assert!(
        !rect_in_region(&e, 0.5, 9.5, 0.5, 2.5),
        "over the hole (centre below it)"
    );
    assert!(!rect_in_region(&e, 9.0, 11.0, 1.0, 2.0), "over the side");
    assert!(!rect_in_region(&e, 11.0, 12.0, 1.0, 2.0), "outside");
    assert!(!rect_in_region(&e, 4.5, 5.5, 2.5, 3.5), "in the hole");
    assert!(!rect_in_region(&e, 1.0, 1.0, 1.0, 2.0), "empty");
}
