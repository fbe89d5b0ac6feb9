use super::*;

#[test]
fn fmt_g_is_c_percent_g() {
    assert_eq!(fmt_g(10.0, 6), "10");
    assert_eq!(fmt_g(2.5, 6), "2.5");
    assert_eq!(fmt_g(0.1, 6), "0.1");
    assert_eq!(fmt_g(90.0, 6), "90");
    assert_eq!(fmt_g(1e-5, 6), "1e-05");
    assert_eq!(fmt_g(0.0001, 6), "0.0001");
    assert_eq!(fmt_g(1234567.0, 6), "1.23457e+06");
    assert_eq!(fmt_g(123456.0, 6), "123456");
    assert_eq!(fmt_g(0.0, 6), "0");
    assert_eq!(fmt_g(12.3456789012, 9), "12.3456789");
    assert_eq!(fmt_g(0.0123456789012, 9), "0.0123456789");
    assert_eq!(fmt_g(1.0e-7, 9), "1e-07");
    assert_eq!(fmt_g(-3.25e12, 9), "-3.25e+12");
}

#[test]
fn merged_control_points_keep_the_inner_ones_first() {
    assert_eq!(merge_control(&[3, 1], &[1, 7, 3, 2]), vec![3, 1, 7, 2]);
    // the hash-set path (many control points) gives the list of the plain scan
    let inner: Vec<usize> = (0..200).map(|i| (i * 37) % 501).collect();
    let outer: Vec<usize> = (0..300).map(|i| (i * 11) % 499).collect();
    let mut plain = inner.clone();
    plain.extend(outer.iter().filter(|i| !inner.contains(i)));
    assert_eq!(merge_control(&inner, &outer), plain);
}

#[test]
fn short_arcs_are_explained() {
    assert!(words::circle_arc(FitCriterion::MaxInscribed, 120.0).is_empty());
    let w = words::circle_arc(FitCriterion::MaxInscribed, 60.04);
    assert_eq!(w[0], "the points cover only 60.0 degrees of arc (< 90): the maximum inscribed circle is ill-posed and its radius is not a meaningful size");
    let w = words::cylinder_arc(FitCriterion::LeastSquares, 45.0);
    assert_eq!(w[0], "the points cover only 45.0 degrees around the axis: axis and radius are poorly determined");
}

#[test]
fn count_settings_are_checked() {
    assert!(count("cylinder", "particles", 0, 1).is_err());
    assert_eq!(count("cylinder", "hop_rounds", 0, 0).unwrap(), 0);
}

#[test]
fn axis_angles_flip_into_the_upper_half_sphere() {
    let (t, _) = axis::axis_angles([0.0, 0.0, -2.0]);
    assert_eq!(t, 0.0);
    let (t, _) = axis::axis_angles([1.0, 0.0, 0.0]);
    assert!((t - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    // along z within rounding: theta 0 and phi 0, whatever the sign of the noise
    for d in [[0.0, -5e-16, 1.0], [3e-17, -2e-16, 1.0], [-1e-12, 0.0, -1.0]] {
        assert_eq!(axis::axis_angles(d), (0.0, 0.0), "{d:?}");
    }
    let (t, p) = axis::axis_angles([0.0, -1e-3, 1.0]);
    assert!(t > 0.0 && (p + std::f64::consts::FRAC_PI_2).abs() < 1e-15);
}
