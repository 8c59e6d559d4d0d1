use metaplate_control::target::*;

#[test]
fn a_delayed_waveform_is_the_same_samples_later() {
    let (len, fs) = (2400, 24_000.0);
    let delay = 120; // samples
    for w in [
        Waveform::NoiseBursts { starts_s: vec![0.01, 0.03], duration_s: 0.005, seed: 3 },
        Waveform::Sine { freq_hz: 200.0, start_s: 0.01, duration_s: 0.02 },
        Waveform::WaveletTrain { freq_hz: 300.0, cycles: 2.0, times_s: vec![0.02, 0.05] },
    ] {
        let (early, late) = (w.samples(len, fs).unwrap(), w.delayed(delay as f64 / fs).samples(len, fs).unwrap());
        for i in 0..len - delay {
            assert!((early[i] - late[i + delay]).abs() < 1e-12, "{w:?} at {i}");
        }
    }
    assert_eq!(Waveform::Impulses { times_s: vec![0.1] }.delayed(0.5), Waveform::Impulses { times_s: vec![0.6] });
    assert_eq!(Waveform::Null.delayed(0.5), Waveform::Null);
}

#[test]
fn one_noise_burst_is_the_noise_waveform_and_a_train_places_each_burst() {
    let (len, fs) = (2400, 24_000.0);
    let single = Waveform::Noise { start_s: 0.01, duration_s: 0.005, seed: 3 }.samples(len, fs).unwrap();
    let train = Waveform::NoiseBursts { starts_s: vec![0.01], duration_s: 0.005, seed: 3 };
    assert_eq!(train.samples(len, fs).unwrap(), single);
    let two = Waveform::NoiseBursts { starts_s: vec![0.01, 0.05], duration_s: 0.005, seed: 3 };
    let x = two.samples(len, fs).unwrap();
    let nonzero: Vec<usize> = (0..len).filter(|&i| x[i] != 0.0).collect();
    assert_eq!(nonzero.first(), Some(&240));
    assert!(nonzero.iter().all(|&i| (240..360).contains(&i) || (1200..1320).contains(&i)));
    assert!(nonzero.iter().any(|&i| i >= 1200));
    let empty = Waveform::NoiseBursts { starts_s: vec![], duration_s: 0.005, seed: 3 };
    assert!(empty.samples(len, fs).is_err());
    let outside = Waveform::NoiseBursts { starts_s: vec![0.2], duration_s: 0.005, seed: 3 };
    assert!(outside.samples(len, fs).is_err());
}
