//! AFL harness for `mp_fuzz::openpose`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::openpose(data);
    });
}
