use super::*;

#[test]
fn rates_parse() {
    assert!((parse_rate("2997/100").unwrap() - 29.97).abs() < 1e-12);
    assert!((parse_rate("30000/1001").unwrap() - 29.97003).abs() < 1e-4);
    assert_eq!(parse_rate("0/0"), None);
    assert_eq!(parse_rate("25").unwrap(), 25.0);
    assert_eq!(parse_rate("x"), None);
}

#[test]
fn probe_json_rotation_swaps_size() {
    let j = r#"{"streams":[{"codec_type":"video","codec_name":"h264","width":640,"height":360,
        "avg_frame_rate":"30/1","nb_frames":"10",
        "side_data_list":[{"rotation":-90}]}],"format":{"duration":"0.33"}}"#;
    let info = parse_probe_json(Path::new("x.mp4"), j).unwrap();
    assert_eq!((info.width, info.height), (360, 640));
    assert_eq!(info.frame_count, Some(10));
    assert_eq!(info.fps, 30.0);
    assert!((info.duration_s.unwrap() - 0.33).abs() < 1e-12);
}

#[test]
fn probe_json_without_video_is_an_error() {
    let j = r#"{"streams":[{"codec_type":"audio"}]}"#;
    let e = parse_probe_json(Path::new("a.mp4"), j).unwrap_err();
    assert!(e.to_string().contains("no video stream"), "{e}");
}

/// A video decoded to YUV 4:2:0 holds the pixels its RGB decoding shows
/// (the odd-sized frames written were padded to even sides); YUV frames
/// encoded again give back those frames, and a frame of another layout's
/// size is refused.
#[test]
fn yuv_frames_decode_and_encode_as_their_rgb() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (63usize, 47usize);
    let rgb: Vec<u8> = (0..w * h)
        .flat_map(|i| {
            let (x, y) = (i % w, i / w);
            [(x * 4) as u8, (y * 5) as u8, 128u8]
        })
        .collect();
    let src = dir.path().join("src.mp4");
    let mut wr = VideoWriter::create_with_preset(&src, w, h, 10.0, "veryfast").unwrap();
    for _ in 0..3 {
        wr.write(&rgb).unwrap();
    }
    wr.finish().unwrap();
    let info = probe(&src).unwrap();
    assert_eq!((info.width, info.height), (w + 1, h + 1));
    let yuv: Vec<Yuv420Frame> = VideoReader::yuv420(info.clone())
        .unwrap()
        .map(|f| f.unwrap())
        .collect();
    let shown: Vec<Vec<u8>> = VideoReader::from_info(info.clone())
        .unwrap()
        .map(|f| f.unwrap().rgb)
        .collect();
    assert_eq!((yuv.len(), shown.len()), (3, 3));
    assert_eq!(
        yuv.iter().map(|f| f.index).collect::<Vec<_>>(),
        vec![0, 1, 2]
    );
    let mean_diff = |a: &[u8], b: &[u8]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| p.abs_diff(*q) as f64)
            .sum::<f64>()
            / a.len() as f64
    };
    let d = mean_diff(&yuv[0].to_rgb(), &shown[0]);
    assert!(d < 2.0, "YUV and RGB decoding differ by {d} levels");
    let out = dir.path().join("again.mp4");
    let mut again = VideoWriter::with_format(
        &out,
        info.width,
        info.height,
        10.0,
        X264 {
            preset: "veryfast",
            params: "subme=1:me=dia",
        },
        PixelFormat::Yuv420p,
    )
    .unwrap();
    let e = again.write(&shown[0]).unwrap_err().to_string();
    assert!(e.contains("YUV"), "{e}");
    for f in &yuv {
        again.write(&f.data).unwrap();
    }
    assert_eq!(again.finish().unwrap(), 3);
    let back: Vec<Vec<u8>> = VideoReader::open(&out)
        .unwrap()
        .map(|f| f.unwrap().rgb)
        .collect();
    assert_eq!(back.len(), 3);
    let d = mean_diff(&back[0], &shown[0]);
    assert!(d < 2.0, "re-encoded YUV frames differ by {d} levels");
}

/// A 30-frame 32 × 32 video in `dir` whose frame `k` is grey level `8 k`.
pub(crate) fn levels_video(dir: &Path) -> VideoInfo {
    let path = dir.join("levels.mp4");
    let (w, h) = (32usize, 32usize);
    let mut wr = VideoWriter::create_with_preset(&path, w, h, 25.0, "veryfast").unwrap();
    for k in 0..30u8 {
        wr.write(&vec![k * 8; w * h * 3]).unwrap();
    }
    wr.finish().unwrap();
    probe(&path).unwrap()
}

/// Decoding from a frame gives the video's own frames from there on.
#[test]
fn decoding_from_a_frame_starts_there() {
    let dir = tempfile::tempdir().unwrap();
    let info = levels_video(dir.path());
    let mean = |f: &Frame| f.rgb.iter().map(|&v| v as f64).sum::<f64>() / f.rgb.len() as f64;
    for start in [0usize, 1, 13, 29] {
        let frames: Vec<Frame> = VideoReader::from_frame(info.clone(), start)
            .unwrap()
            .map(|f| f.unwrap())
            .collect();
        assert_eq!(frames.len(), 30 - start, "from {start}");
        for (i, f) in frames.iter().enumerate() {
            assert_eq!(f.index, i);
            let want = ((start + i) * 8) as f64;
            assert!(
                (mean(f) - want).abs() < 3.0,
                "frame {}: {} vs {want}",
                start + i,
                mean(f)
            );
        }
    }
    // Past the end: no frame (a clear error where FFmpeg gave none).
    let past: Vec<_> = VideoReader::from_frame(info, 40).unwrap().collect();
    assert!(
        past.iter().all(|f| f.is_err()),
        "{} frames past the end",
        past.len()
    );
}

#[test]
fn frame_checks_buffer_size() {
    assert!(Frame::new(3, 0.0, 2, 2, vec![0; 11]).is_err());
    assert!(Frame::new(3, 0.0, 0, 2, vec![]).is_err());
    assert!(Frame::new(3, 0.0, 2, 2, vec![0; 12]).is_ok());
}

/// x264's options are checked before FFmpeg starts: a known preset, and
/// `key=value` pairs joined by `:`.
#[test]
fn x264_options_are_checked() {
    assert!(X264::preset("veryfast").validate().is_ok());
    let ok = X264 {
        preset: "veryfast",
        params: "subme=1:me=dia:partitions=none",
    };
    assert!(ok.validate().is_ok());
    for (preset, params) in [
        ("quick", ""),
        ("veryfast", "subme"),
        ("veryfast", "subme=1:"),
        ("veryfast", "=1"),
        ("veryfast", "subme=1 me=dia"),
        ("veryfast", "a=b=c"),
    ] {
        let e = X264 { preset, params }.validate().unwrap_err().to_string();
        assert!(
            e.contains(if preset == "quick" {
                "preset"
            } else {
                "x264 params"
            }),
            "{e}"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let bad = X264 {
        preset: "veryfast",
        params: "subme",
    };
    let e = VideoWriter::with_format(
        dir.path().join("x.mp4"),
        8,
        8,
        10.0,
        bad,
        PixelFormat::Rgb24,
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("subme"), "{e}");
}
