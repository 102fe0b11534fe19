//! AFL harness for `mp_fuzz::mpb`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::mpb(data);
    });
}
