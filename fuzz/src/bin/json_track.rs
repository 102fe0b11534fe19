//! AFL harness for `mp_fuzz::json_track`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::json_track(data);
    });
}
