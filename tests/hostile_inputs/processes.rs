//! A bake killed, or on a full disk: no store left half written, the old one kept.

#[allow(unused_imports)]
use super::*;

#[cfg(unix)]
#[test]
fn a_killed_bake_leaves_no_store_and_keeps_the_old_one() {
    use std::os::unix::process::ExitStatusExt;

    let dir = common::temp_dir("hostile-kill");
    // Big enough that the bake runs for seconds, so the signal lands mid-bake.
    let city = gen_city(&dir, "city.geojson", 1500);
    let small = gen_city(&dir, "small.geojson", 60);
    let c = city.to_str().unwrap();

    // A complete small store: the "previous" output, and the bytes a killed write could have
    // left a prefix of. No proper prefix of it parses.
    let old = dir.join("old.vocc");
    let o = vocc(&bake_args(small.to_str().unwrap(), old.to_str().unwrap()));
    assert!(o.status.success(), "{}", stderr(&o));
    let old_bytes = std::fs::read(&old).unwrap();
    assert!(Store::parse(&old_bytes).is_ok());
    for len in 0..old_bytes.len() {
        assert!(
            Store::parse(&old_bytes[..len]).is_err(),
            "prefix of {len} bytes parses"
        );
    }

    for (signal, name) in [(9, "KILL"), (2, "INT")] {
        for previous in [false, true] {
            let out = dir.join(format!("sig{name}-{previous}.vocc"));
            if previous {
                std::fs::write(&out, &old_bytes).unwrap();
            }
            // A shell without job control starts background jobs with SIGINT ignored, and the
            // child inherits that (as under `make fresh-clone &`): the bake then ran to its end
            // and exited 0. Give it the default action back, as a terminal's Ctrl-C would meet.
            let mut cmd = if signal == 2 && sigint_ignored() {
                let mut e = Command::new("env");
                e.arg("--default-signal=INT").arg(common::vocc_bin());
                e
            } else {
                Command::new(common::vocc_bin())
            };
            let mut child = cmd
                .args(bake_args(c, out.to_str().unwrap()))
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .spawn()
                .unwrap();
            std::thread::sleep(Duration::from_millis(1000));
            assert!(
                child.try_wait().unwrap().is_none(),
                "the bake ended before SIG{name}: make the city bigger"
            );
            let sent = Command::new("kill")
                .args([&format!("-{name}"), &child.id().to_string()])
                .status()
                .unwrap();
            assert!(sent.success());
            let status = child.wait().unwrap();
            assert_eq!(status.signal(), Some(signal), "SIG{name}: {status:?}");
            if previous {
                assert_eq!(
                    std::fs::read(&out).unwrap(),
                    old_bytes,
                    "SIG{name} changed the old store"
                );
            } else {
                assert!(!out.exists(), "SIG{name} left a store behind");
            }
            let tmp = temp_of(&out);
            if let Ok(b) = std::fs::read(&tmp) {
                assert!(
                    Store::parse(&b).is_err(),
                    "SIG{name} left a valid temp store"
                );
            }
        }
    }
}

/// A real full disk: a 64 KiB tmpfs filled to the last block, mounted in a private namespace.
/// `vocc bake` into it must fail saying the disk is full and leave no store and no temporary file;
/// `vocc gen-city` writing more than the whole disk holds must fail the same way. Set
/// `VOCC_SKIP_FULL_DISK=1` where `unshare` cannot map a user namespace (the test then only checks
/// that the variable is the reason it did nothing).
#[cfg(target_os = "linux")]
#[test]
fn a_full_disk_is_reported_and_leaves_nothing() {
    let dir = common::temp_dir("hostile-full-disk");
    let small = gen_city(&dir, "small.geojson", 60);
    let mnt = dir.join("mnt");
    std::fs::create_dir_all(&mnt).unwrap();
    let script = r#"
        mount -t tmpfs -o size=64k tmpfs "$MNT" || exit 90
        cat /dev/zero > "$MNT/fill" 2>/dev/null
        echo "== bake"
        "$VOCC" bake "$SCENE" --height-attr height --cell-size 40 --threads 1 -o "$MNT/out.vocc" 2>&1
        echo "rc=$?"
        ls -A "$MNT"
        rm "$MNT/fill"
        echo "== gen-city"
        "$VOCC" gen-city --buildings 3000 -o "$MNT/city.geojson" 2>&1
        echo "rc=$?"
        ls -A "$MNT"
        echo "== end"
    "#;
    let env = [
        ("MNT", mnt.to_str().unwrap()),
        ("VOCC", common::vocc_bin()),
        ("SCENE", small.to_str().unwrap()),
    ];
    let Some(o) = in_private_mount_namespace(script, &env) else {
        assert!(
            std::env::var_os("VOCC_SKIP_FULL_DISK").is_some(),
            "cannot mount a tmpfs in a private namespace (unshare --user --map-root-user \
             --mount); set VOCC_SKIP_FULL_DISK=1 to skip this test on such a machine"
        );
        return;
    };
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    // The script's output in sections: "bake\n...", "gen-city\n...", "end\n".
    let section = |name: &str| -> String {
        let head = format!("{name}\n");
        text.split("== ")
            .find(|s| s.starts_with(&head))
            .unwrap_or_else(|| panic!("no section {name}: {text}"))
            .to_string()
    };
    let bake = section("bake");
    assert!(bake.contains("rc=1"), "{text}");
    assert!(bake.contains("the disk is full"), "{text}");
    assert!(bake.contains("out.vocc"), "names the output: {text}");
    assert!(!bake.contains("panicked"), "{text}");
    let listing: Vec<&str> = bake
        .lines()
        .skip_while(|l| !l.starts_with("rc="))
        .skip(1)
        .collect();
    assert_eq!(listing, ["fill"], "only the filler remains: {text}");

    let gen = section("gen-city");
    assert!(gen.contains("rc=1"), "{text}");
    assert!(gen.contains("the disk is full"), "{text}");
    assert!(gen.contains("city.geojson"), "{text}");
    let listing: Vec<&str> = gen
        .lines()
        .skip_while(|l| !l.starts_with("rc="))
        .skip(1)
        .collect();
    assert!(listing.is_empty(), "nothing remains: {text}");
    assert!(text.contains("== end"), "{text}");
}
