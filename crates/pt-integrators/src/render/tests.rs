use super::*;

/// The shares of a split render take every sample index exactly once, interleaved, and
/// their sample counts are what `samples_of` says.
#[test]
fn shares_take_every_sample_once() {
    for spp in [1, 2, 7, 64, 1000] {
        for count in [1, 2, 3, 4, 8, 13] {
            let mut seen = vec![0u32; spp as usize];
            for index in 0..count {
                let share = Share { index, count };
                for local in 0..share.samples_of(spp) {
                    seen[share.sample(local) as usize] += 1;
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "spp {spp}, {count} shares");
        }
    }
    assert_eq!(Share::WHOLE.samples_of(5), 5);
    assert_eq!(Share { index: 2, count: 4 }.sample(3), 14);
}
