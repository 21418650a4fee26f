//! Laser telegrams as scans: the one place where a telegram decoded by `crate::wire` (ranges
//! in the laser's units, angles as the laser counts them) becomes a [`Scan`] (metres, radians,
//! laser frame: x forward, counter-clockwise positive).
//!
//! - LMS1xx ([`lms1xx_scan`]): SICK counts the start angle from the laser's right-hand side
//!   (its 0° is the laser frame's −90°), so beam `i` lies at `start/10000° − 90° + i ·
//!   step/10000°` (the clearpath LMS1xx driver's rule); range = value × scale + offset \[mm\].
//! - LMS200 ([`lms200_scan`]): the scan is centred on forward and sweeps from the laser's
//!   right to its left ([`Variant::first_angle_cdeg`]), one beam per resolution step.
//!
//! A zero value (no return) and a range beyond the usable range become "no return".

use core::fmt;

use super::{Beam, Scan, ScanError};
use crate::units::{deg_to_rad, mm_to_m};
use crate::wire::lms1xx::ScanTelegram;
use crate::wire::lms200::{MeasuredValues, Variant};

/// Errors converting an LMS1xx telegram into a [`Scan`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum ToScanError {
    /// No `DIST` channel in the telegram.
    NoDistanceChannel,
    /// A scale factor or offset that is not finite.
    BadScale {
        /// The scale factor.
        scale: f32,
        /// The offset.
        offset: f32,
    },
    /// The scan cannot hold the beams.
    Scan(ScanError),
}

impl fmt::Display for ToScanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ToScanError::NoDistanceChannel => write!(f, "telegram has no DIST channel"),
            ToScanError::BadScale { scale, offset } => {
                write!(f, "scale factor {scale} / offset {offset} not finite")
            }
            ToScanError::Scan(e) => write!(f, "{e}"),
        }
    }
}

impl core::error::Error for ToScanError {}

impl From<ScanError> for ToScanError {
    fn from(e: ScanError) -> Self {
        ToScanError::Scan(e)
    }
}

/// An LMS1xx telegram's distance channel as a scan in `out` (cleared first). Ranges above
/// `max_range_m` \[m\] become "no return".
pub fn lms1xx_scan(t: &ScanTelegram, max_range_m: f32, out: &mut Scan) -> Result<(), ToScanError> {
    let c = t.distance_channel().ok_or(ToScanError::NoDistanceChannel)?;
    if !c.scale.is_finite() || !c.offset.is_finite() {
        return Err(ToScanError::BadScale {
            scale: c.scale,
            offset: c.offset,
        });
    }
    out.clear();
    let start = c.start_angle_deg_e4 as f64;
    let step = c.step_deg_e4 as f64;
    for (i, &v) in c.values.iter().enumerate() {
        let angle_deg = (start + i as f64 * step) / 10_000.0 - 90.0;
        let range_mm = v as f32 * c.scale + c.offset;
        let range_m = mm_to_m(range_mm);
        let range_m = (v != 0 && range_m > 0.0 && range_m <= max_range_m).then_some(range_m);
        out.push(Beam {
            angle_rad: deg_to_rad(angle_deg as f32),
            range_m,
        })?;
    }
    Ok(())
}

/// The first beam's angle of an LMS200 scan with `variant` \[rad\] (−π/2 for 180°).
pub fn lms200_first_angle_rad(variant: Variant) -> f32 {
    deg_to_rad(variant.first_angle_cdeg() as f32 / 100.0)
}

/// The beam step of an LMS200 scan with `variant` \[rad\].
pub fn lms200_step_rad(variant: Variant) -> f32 {
    deg_to_rad(variant.resolution_cdeg as f32 / 100.0)
}

/// An LMS200 measured-values telegram taken with `variant` as a scan in `out` (cleared
/// first). `distance_mask` keeps the distance bits (0x1FFF for 13-bit mm data); ranges above
/// `max_range_m` \[m\] become "no return".
pub fn lms200_scan(
    m: &MeasuredValues,
    variant: Variant,
    distance_mask: u16,
    max_range_m: f32,
    out: &mut Scan,
) -> Result<(), ScanError> {
    let first_angle_rad = lms200_first_angle_rad(variant);
    let step_rad = lms200_step_rad(variant);
    out.clear();
    for (i, mm) in m.ranges_mm(distance_mask).enumerate() {
        let range_m = mm_to_m(mm as f32);
        let range_m = (mm != 0 && range_m <= max_range_m).then_some(range_m);
        out.push(Beam {
            angle_rad: first_angle_rad + i as f32 * step_rad,
            range_m,
        })?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn golden_lms1xx_telegram_as_a_scan() {
        let frame = crate::wire::lms1xx::scandata::tests::lms1xx_telegram();
        let t = ScanTelegram::parse(&frame[1..frame.len() - 1]).unwrap();
        let mut scan = Scan::new();
        lms1xx_scan(&t, 4.0, &mut scan).unwrap();
        let b = scan.beams();
        assert_eq!(b.len(), 541);
        assert!((b[0].angle_rad - deg_to_rad(-135.0)).abs() < 1e-6);
        assert!((b[270].angle_rad).abs() < 1e-6);
        assert!((b[540].angle_rad - deg_to_rad(135.0)).abs() < 1e-5);
        assert_eq!(b[0].range_m, None, "0 = no return");
        let near = |r: Option<f32>, m: f32| r.is_some_and(|r| (r - m).abs() < 1e-5);
        assert!(near(b[1].range_m, 0.51));
        assert!(near(b[350].range_m, 4.0), "4.0 m is at the usable range");
        assert_eq!(b[351].range_m, None, "4.01 m is beyond the usable range");
        assert_eq!(b[300].range_m, None);
    }

    #[test]
    fn lms200_measured_values_as_a_scan() {
        let mut m = MeasuredValues::default();
        for i in 0..181u16 {
            m.values.push(if i == 90 { 0 } else { 1000 + i }).unwrap();
        }
        let v = Variant::DEG180_RES1;
        let mut scan = Scan::new();
        lms200_scan(&m, v, 0x1FFF, 1.1, &mut scan).unwrap();
        assert_eq!(scan.len(), v.beam_count());
        let b = scan.beams();
        assert!((b[0].angle_rad + core::f32::consts::FRAC_PI_2).abs() < 1e-6);
        assert!((b[180].angle_rad - core::f32::consts::FRAC_PI_2).abs() < 1e-4);
        assert_eq!(b[0].range_m, Some(1.0));
        assert_eq!(b[90].range_m, None);
        assert_eq!(
            b[150].range_m, None,
            "1.150 m is beyond the 1.1 m usable range"
        );
    }
}
