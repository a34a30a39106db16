//! The contact map's colour scale: bands like articulating paper's marks, 0–0.5 mm.

/// The bands of [`gap_colour`]: (upper end of the band in mm, colour name, RGB). A gap in
/// no band (above 0.5 mm) is light grey.
pub const LEGEND: [(f64, &str, [u8; 3]); 6] = [
    (0.0, "inside the other arch (< 0)", [128, 0, 160]),
    (0.05, "tight contact (0–0.05)", [220, 20, 20]),
    (0.1, "contact (0.05–0.1)", [255, 140, 0]),
    (0.2, "near contact (0.1–0.2)", [245, 220, 0]),
    (0.3, "close (0.2–0.3)", [40, 180, 60]),
    (0.5, "clear (0.3–0.5)", [40, 110, 230]),
];

/// Light grey: farther than the last band.
const FAR: [u8; 3] = [200, 200, 200];

/// The colour of a signed gap (mm): the first band of [`LEGEND`] whose upper end is above
/// the gap (or reaches it, for 0.5); light grey beyond 0.5 mm or for NaN.
pub fn gap_colour(gap: f64) -> [u8; 3] {
    if gap.is_nan() {
        return FAR;
    }
    for (k, &(hi, _, rgb)) in LEGEND.iter().enumerate() {
        if gap < hi || (k == LEGEND.len() - 1 && gap <= hi) {
            return rgb;
        }
    }
    FAR
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands() {
        assert_eq!(gap_colour(-1.0), LEGEND[0].2);
        assert_eq!(gap_colour(0.0), LEGEND[1].2);
        assert_eq!(gap_colour(0.07), LEGEND[2].2);
        assert_eq!(gap_colour(0.5), LEGEND[5].2);
        assert_eq!(gap_colour(0.51), FAR);
        assert_eq!(gap_colour(f64::NAN), FAR);
        assert_eq!(gap_colour(f64::INFINITY), FAR);
    }
}
