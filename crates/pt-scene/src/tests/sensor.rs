//! Sensor, film, sampler and integrators.

use super::*;

#[test]
fn missing_sensor_and_integrator_use_mitsuba_defaults() {
    let s = load(&scene("<shape type=\"cube\"/>")).unwrap();
    assert_eq!(
        s.camera.projection,
        Projection::Perspective {
            fov_deg: 45.0,
            fov_axis: FovAxis::X
        }
    );
    assert_eq!((s.film.width, s.film.height), (768, 576));
    assert_eq!(s.film.filter, FilterDesc::Gaussian { stddev: 0.5 });
    assert_eq!((s.sampler.sample_count, s.sampler.seed), (4, 0));
    assert_eq!(s.integrator.kind, IntegratorKind::Path);
    assert_eq!(
        (
            s.integrator.max_depth,
            s.integrator.rr_depth,
            s.integrator.hide_emitters
        ),
        (-1, 5, false)
    );
    // The camera backs off along -z until the whole [-1, 1]^3 cube fits in 45 degrees.
    let eye = s.camera.to_world.transform_point3(Vec3::ZERO);
    let distance = 2.0 / (2.0 * 22.5f32.to_radians().tan());
    assert!(close(eye, Vec3::new(0.0, 0.0, -1.0 - distance)), "{eye}");

    let empty = load(&scene("")).unwrap();
    assert_eq!(empty.camera.to_world, glam::Mat4::IDENTITY);
    assert!(empty.shapes.is_empty());
}

#[test]
fn sensor_parameters() {
    let s = load(&scene(
        r#"<sensor type="perspective">
    <string name="focal_length" value="35mm"/>
    <float name="near_clip" value="0.5"/>
    <sampler type="stratified"><integer name="sample_count" value="10"/><integer name="seed" value="7"/><boolean name="jitter" value="false"/></sampler>
    <film type="hdrfilm">
        <integer name="height" value="100"/>
        <string name="pixel_format" value="RGBA"/>
        <string name="component_format" value="float32"/>
        <boolean name="banner" value="false"/>
        <boolean name="sample_border" value="false"/>
        <integer name="crop_offset_x" value="0"/>
        <integer name="crop_height" value="100"/>
        <rfilter type="tent"><float name="radius" value="1.5"/></rfilter>
    </film>
</sensor>"#,
    ))
    .unwrap();
    let fov = 2.0 * (43.266_615f32 / 70.0).atan().to_degrees();
    match s.camera.projection {
        Projection::Perspective { fov_deg, fov_axis } => {
            assert!((fov_deg - fov).abs() < 1e-3, "{fov_deg} vs {fov}");
            assert_eq!(fov_axis, FovAxis::Diagonal);
        }
        ref p => panic!("{p:?}"),
    }
    assert_eq!(s.camera.near_clip, 0.5);
    assert_eq!(
        (s.sampler.sample_count, s.sampler.seed),
        (16, 7),
        "stratified rounds up to a square"
    );
    assert_eq!((s.film.width, s.film.height), (768, 100));
    assert_eq!(s.film.crop, None, "a window of the whole film is no crop");
    assert_eq!(s.film.filter, FilterDesc::Tent { radius: 1.5 });
}

#[test]
fn crop_window_and_principal_point() {
    let s = load(&scene(
        r#"<sensor type="perspective">
    <float name="principal_point_offset_x" value="0.12"/>
    <float name="principal_point_offset_y" value="-0.08"/>
    <film type="hdrfilm">
        <integer name="width" value="112"/><integer name="height" value="64"/>
        <integer name="crop_offset_x" value="24"/><integer name="crop_width" value="64"/>
    </film>
</sensor>"#,
    ))
    .unwrap();
    assert_eq!(s.camera.principal_point_offset, [0.12, -0.08]);
    // Only the width is cropped: crop_height defaults to the film's height.
    assert_eq!((s.film.width, s.film.height), (64, 64));
    assert_eq!(
        s.film.crop,
        Some(CropWindow {
            offset: [24, 0],
            film_size: [112, 64]
        })
    );
    assert_eq!(s.film.film_size(), [112, 64]);
    // thinlens has no principal point in Mitsuba: the parameter is refused as unused.
    let e = fail(&scene(
        r#"<sensor type="thinlens"><float name="aperture_radius" value="0"/>
    <float name="principal_point_offset_x" value="0.1"/></sensor>"#,
    ));
    assert!(
        e.message
            .contains("unused property 'principal_point_offset_x'"),
        "{e}"
    );
}

#[test]
fn sensor_errors() {
    let sensor = |inner: &str| {
        scene(&format!(
            "<sensor type=\"perspective\">\n{inner}\n</sensor>"
        ))
    };
    let cases = [
        ("<string name=\"fov_axis\" value=\"z\"/>\n<float name=\"fov\" value=\"30\"/>", 3, "fov_axis must be"),
        ("<float name=\"fov\" value=\"180\"/>", 3, "between 0 and 180"),
        ("<float name=\"near_clip\" value=\"10\"/><float name=\"far_clip\" value=\"1\"/>", 3, "smaller than far_clip"),
        ("<float name=\"fov\" value=\"30\"/><string name=\"focal_length\" value=\"50mm\"/>", 3, "not both"),
        ("<string name=\"focal_length\" value=\"long\"/>", 3, "focal length"),
        ("<transform name=\"to_world\"><scale value=\"2\"/></transform>", 3, "may only rotate"),
        ("<film type=\"hdrfilm\"><integer name=\"width\" value=\"0\"/></film>", 3, "between 1 and"),
        ("<film type=\"hdrfilm\"><integer name=\"crop_offset_x\" value=\"700\"/><integer name=\"crop_width\" value=\"100\"/></film>", 3, "reaches past the film"),
        ("<film type=\"hdrfilm\"><integer name=\"crop_offset_y\" value=\"10\"/></film>", 3, "reaches past the film"),
        ("<film type=\"hdrfilm\"><integer name=\"crop_height\" value=\"0\"/></film>", 3, "between 1 and 576"),
        ("<float name=\"principal_point_offset_x\" value=\"nan\"/>", 3, "is not finite"),
        ("<film type=\"hdrfilm\"><string name=\"pixel_format\" value=\"cmyk\"/></film>", 3, "pixel_format"),
        ("<film type=\"hdrfilm\"><rfilter type=\"box\"><float name=\"radius\" value=\"1\"/></rfilter></film>", 3, "unused property 'radius'"),
        ("<sampler type=\"independent\"><integer name=\"sample_count\" value=\"0\"/></sampler>", 3, "at least 1"),
        ("<film type=\"hdrfilm\"/>\n<film type=\"hdrfilm\"/>", 4, "only one <film>"),
        ("<string name=\"fov_axis\" value=\"y\"/>", 3, "unused property 'fov_axis'"),
    ];
    for (inner, line, text) in cases {
        let e = fail(&sensor(inner));
        assert_eq!(e.loc.as_ref().map(|l| l.line), Some(line), "{inner}: {e}");
        assert!(
            e.message.contains(text),
            "{inner}: expected '{text}' in {e}"
        );
    }
    assert!(fail(&scene(
        "<sensor type=\"perspective\"/>\n<sensor type=\"perspective\"/>"
    ))
    .message
    .contains("only one <sensor>"));
}

#[test]
fn integrators() {
    let integrator = |xml: &str| load(&scene(xml)).map(|s| s.integrator);
    let i = integrator("<integrator type=\"path\"><integer name=\"max_depth\" value=\"0\"/><boolean name=\"hide_emitters\" value=\"true\"/></integrator>").unwrap();
    assert_eq!((i.max_depth, i.hide_emitters), (0, true));
    let i = integrator(
        "<integrator type=\"direct\"><integer name=\"emitter_samples\" value=\"1\"/></integrator>",
    )
    .unwrap();
    assert_eq!(
        (i.kind, i.max_depth),
        (
            IntegratorKind::Direct {
                emitter_samples: 1,
                bsdf_samples: 1
            },
            2
        )
    );
    let i = integrator("<integrator type=\"moment\"><integrator type=\"path\"><integer name=\"max_depth\" value=\"3\"/></integrator></integrator>").unwrap();
    assert_eq!(
        (i.kind, i.max_depth, i.moment.as_deref()),
        (IntegratorKind::Path, 3, Some("_arg_0"))
    );

    // Mitsuba's differentiable integrators: path or volpath with their own defaults (depth 6)
    // and roulette one vertex later; prb_projective's gradient options accepted.
    let i = integrator("<integrator type=\"prb\"/>").unwrap();
    assert_eq!(
        (i.kind, i.max_depth, i.rr_depth),
        (IntegratorKind::Path, 6, 6)
    );
    let i = integrator("<integrator type=\"prbvolpath\"><integer name=\"max_depth\" value=\"-1\"/><integer name=\"rr_depth\" value=\"3\"/></integrator>").unwrap();
    assert_eq!(
        (i.kind, i.max_depth, i.rr_depth),
        (IntegratorKind::VolPath, -1, 4)
    );
    let i = integrator("<integrator type=\"prb_projective\"><integer name=\"sppc\" value=\"32\"/><integer name=\"sppp\" value=\"16\"/><integer name=\"sppi\" value=\"64\"/><string name=\"guiding\" value=\"octree\"/><boolean name=\"guiding_proj\" value=\"true\"/><integer name=\"guiding_rounds\" value=\"1\"/></integrator>").unwrap();
    assert_eq!((i.kind, i.max_depth), (IntegratorKind::Path, 6));
    assert!(i.light_sampling);
    let i = integrator("<integrator type=\"prb_basic\"><boolean name=\"hide_emitters\" value=\"true\"/></integrator>").unwrap();
    assert_eq!(
        (
            i.kind,
            i.max_depth,
            i.rr_depth,
            i.hide_emitters,
            i.light_sampling
        ),
        (IntegratorKind::Path, 6, u32::MAX, false, false)
    );

    let cases = [
        (
            "<integer name=\"max_depth\" value=\"-2\"/>",
            "path",
            "at least -1",
        ),
        (
            "<integer name=\"sppc\" value=\"8\"/>",
            "prb",
            "unused property 'sppc'",
        ),
        (
            "<integer name=\"rr_depth\" value=\"0\"/>",
            "path",
            "at least 1",
        ),
        (
            "<integer name=\"bsdf_samples\" value=\"4\"/><integer name=\"shading_samples\" value=\"2\"/>",
            "direct",
            "Mitsuba refuses both",
        ),
        (
            "<integer name=\"max_depth\" value=\"3\"/>",
            "direct",
            "unused property 'max_depth'",
        ),
        ("", "moment", "needs one nested"),
        // moment and aov wrap camera path tracers only: a light tracer's or BDPT's image is
        // not a mean of per-pixel samples whose second moment could be taken.
        (
            "<integrator type=\"ptracer\"/>",
            "moment",
            "nested in moment must be path, volpath or direct",
        ),
        (
            "<string name=\"aovs\" value=\"d:depth\"/><integrator type=\"bdpt\"/>",
            "aov",
            "nested in aov must be path, volpath, direct or moment",
        ),
        ("<shape type=\"cube\"/>", "path", "cannot be nested"),
    ];
    for (inner, plugin, text) in cases {
        let e = fail(&scene(&format!(
            "<integrator type=\"{plugin}\">\n{inner}\n</integrator>"
        )));
        assert!(
            e.message.contains(text),
            "{inner}: expected '{text}' in {e}"
        );
    }
    assert!(fail(&scene(
        "<integrator type=\"path\"/><integrator type=\"path\"/>"
    ))
    .message
    .contains("only one"));
}

/// Mitsuba's `aov`: its outputs in order with Mitsuba's channel names, the nested integrator's
/// settings and name, AOVs alone (a default path tracer whose image is not rendered), and
/// located errors for what it refuses.
#[test]
fn aov_integrator() {
    let integrator = |xml: &str| load(&scene(xml)).map(|s| s.integrator);
    let i = integrator(
        r#"<integrator type="aov"><string name="aovs" value="dd.y:depth, nn:sh_normal,a:albedo"/>
        <integrator type="path" name="my_image"><integer name="max_depth" value="3"/></integrator></integrator>"#,
    )
    .unwrap();
    assert_eq!((i.kind, i.max_depth), (IntegratorKind::Path, 3));
    let aov = i.aov.expect("aov");
    assert_eq!(aov.image.as_deref(), Some("my_image"));
    assert_eq!(
        aov.channel_names(),
        [
            "my_image.R",
            "my_image.G",
            "my_image.B",
            "my_image.A",
            "dd.y.T",
            "nn.X",
            "nn.Y",
            "nn.Z",
            "a.R",
            "a.G",
            "a.B"
        ]
    );
    let i = integrator(
        r#"<integrator type="aov"><string name="aovs" value="p:position uv:uv"/></integrator>"#,
    )
    .unwrap();
    let aov = i.aov.expect("aov");
    assert_eq!(aov.image, None);
    assert_eq!(aov.channel_names(), ["p.X", "p.Y", "p.Z", "uv.U", "uv.V"]);
    assert!(aov.needs_uv());

    let cases = [
        ("", "needs <string name=\"aovs\""),
        ("<string name=\"aovs\" value=\"depth\"/>", "not a <name>:<type> pair"),
        ("<string name=\"aovs\" value=\"d:distance\"/>", "invalid AOV type \"distance\""),
        ("<string name=\"aovs\" value=\"d:duv_dx\"/>", "not yet implemented"),
        (
            "<string name=\"aovs\" value=\"d:depth\"/><integrator type=\"path\"/><integrator type=\"path\"/>",
            "more than one nested integrator",
        ),
        (
            "<string name=\"aovs\" value=\"d:depth\"/><integrator type=\"radiosity\"/>",
            "must be path, volpath, direct or moment",
        ),
        ("<string name=\"aovs\" value=\"d:depth\"/><integer name=\"max_depth\" value=\"3\"/>", "unused property 'max_depth'"),
    ];
    for (inner, text) in cases {
        let e = fail(&scene(&format!(
            "<integrator type=\"aov\">\n{inner}\n</integrator>"
        )));
        assert!(e.loc.is_some(), "{inner}: {e}");
        assert!(
            e.message.contains(text),
            "{inner}: expected '{text}' in {e}"
        );
    }
}

/// `pixel_format` parses every Mitsuba name (any case) to its channels.
#[test]
fn pixel_formats() {
    for (name, channels) in [
        ("rgb", &["R", "G", "B"][..]),
        ("RGBA", &["R", "G", "B", "A"]),
        ("luminance", &["Y"]),
        ("luminance_alpha", &["Y", "A"]),
        ("xyz", &["X", "Y", "Z"]),
        ("xyza", &["X", "Y", "Z", "A"]),
    ] {
        let s = load(&scene(&format!(
            r#"<sensor type="perspective"><film type="hdrfilm"><string name="pixel_format" value="{name}"/></film></sensor>"#
        )))
        .unwrap();
        assert_eq!(s.film.pixel_format.channels(), channels, "{name}");
    }
    let s = load(&scene(r#"<sensor type="perspective"/>"#)).unwrap();
    assert_eq!(s.film.pixel_format, PixelFormat::Rgb);
}

// -------------------------------------------------------------------------------------------
// Transforms through whole scenes, and old scenes

/// `thinlens` needs its aperture, defaults its focus to the far clip plane (Mitsuba), and
/// `orthographic` takes a scaling `to_world`.
#[test]
fn thin_lens_and_orthographic_sensors() {
    let s = load(&scene(
        r#"<sensor type="thinlens"><float name="aperture_radius" value="0.25"/><float name="far_clip" value="50"/></sensor>"#,
    ))
    .unwrap();
    match s.camera.projection {
        Projection::ThinLens {
            aperture_radius,
            focus_distance,
            ..
        } => assert_eq!((aperture_radius, focus_distance), (0.25, 50.0)),
        ref p => panic!("{p:?}"),
    }
    let e = fail(&scene(r#"<sensor type="thinlens"/>"#));
    assert_error(&e, 2, "sensor type=\"thinlens\"", "aperture_radius");
    let e = fail(&scene(
        r#"<sensor type="thinlens"><float name="aperture_radius" value="-1"/></sensor>"#,
    ));
    assert!(e.message.contains("aperture_radius must be >= 0"), "{e}");
    let s = load(&scene(
        r#"<sensor type="orthographic"><transform name="to_world"><scale value="3"/></transform></sensor>"#,
    ))
    .unwrap();
    assert_eq!(s.camera.projection, Projection::Orthographic);
    assert_eq!(s.camera.to_world.x_axis.x, 3.0);
    let e = fail(&scene(
        r#"<sensor type="orthographic"><transform name="to_world"><scale value="0"/></transform></sensor>"#,
    ));
    assert!(e.message.contains("invertible"), "{e}");
}

/// `radiancemeter`: origin and direction (or to_world) make a camera looking along +z; it
/// needs a 1 x 1 film and refuses both ways of placing it at once.
#[test]
fn radiancemeter_is_one_ray() {
    let film = r#"<film type="hdrfilm"><integer name="width" value="1"/><integer name="height" value="1"/></film>"#;
    let sensor = |inner: &str| {
        load(&format!(
            "<scene version=\"3.0.0\"><sensor type=\"radiancemeter\">{inner}</sensor></scene>"
        ))
    };
    let s = sensor(&format!(
        r#"<point name="origin" value="1, 2, 3"/><vector name="direction" value="0, 0, -2"/>{film}"#
    ))
    .unwrap();
    assert_eq!(s.camera.projection, Projection::Radiancemeter);
    let m = s.camera.to_world;
    assert!((m.transform_point3(Vec3::ZERO) - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-6);
    assert!((m.transform_vector3(Vec3::Z) - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
    for (inner, want) in [
        (String::new(), "needs a 1 x 1 film"),
        (
            format!(
                r#"<point name="origin" value="0, 0, 0"/><transform name="to_world"><translate value="1, 0, 0"/></transform>{film}"#
            ),
            "not both",
        ),
        (
            format!(r#"<vector name="direction" value="0, 0, 0"/>{film}"#),
            "non-zero",
        ),
    ] {
        let e = sensor(&inner).unwrap_err();
        assert!(e.message.contains(want), "{inner}: {e}");
    }
}

/// `irradiancemeter`: nested in a shape it becomes the scene's sensor, numbered with that
/// shape (after the shapes before it); it needs a 1 x 1 film, a shape, and a scene without
/// another sensor; a shape holds no other kind of sensor.
#[test]
fn irradiancemeter_measures_its_shape() {
    let film = r#"<film type="hdrfilm"><integer name="width" value="1"/><integer name="height" value="1"/></film>"#;
    let meter = format!(r#"<sensor type="irradiancemeter">{film}</sensor>"#);
    let s = load(&format!(
        r#"<scene version="3.0.0"><shape type="sphere"/><shape type="rectangle">{meter}</shape><shape type="cube"/></scene>"#
    ))
    .unwrap();
    assert_eq!(
        s.camera.projection,
        Projection::Irradiancemeter { shape: 1 }
    );
    assert_eq!((s.film.width, s.film.height), (1, 1));
    for (xml, want) in [
        (format!("<scene version=\"3.0.0\">{meter}</scene>"), "must be nested in the <shape>"),
        (
            r#"<scene version="3.0.0"><shape type="sphere"><sensor type="irradiancemeter"/></shape></scene>"#.to_string(),
            "needs a 1 x 1 film",
        ),
        (
            r#"<scene version="3.0.0"><shape type="sphere"><sensor type="perspective"/></shape></scene>"#.to_string(),
            "cannot be nested in shape",
        ),
        (
            format!(r#"<scene version="3.0.0"><sensor type="perspective"/><shape type="sphere">{meter}</shape></scene>"#),
            "only one <sensor>",
        ),
        (
            format!(r#"<scene version="3.0.0"><shape type="shapegroup" id="g"><shape type="sphere">{meter}</shape></shape></scene>"#),
            "shapegroup cannot hold a sensor",
        ),
    ] {
        let e = load(&xml).unwrap_err();
        assert!(e.message.contains(want), "{xml}: {e}");
    }
}

/// `distant`: its direction (default +z) and target (the bounding disk, a point, or a nested
/// shape kept apart from the scene's shapes); a 1 x 1 film; not a point and a shape at once.
#[test]
fn distant_sensor_reads_its_direction_and_target() {
    let film = r#"<film type="hdrfilm"><integer name="width" value="1"/><integer name="height" value="1"/></film>"#;
    let sensor = |inner: &str| {
        load(&format!(
            r#"<scene version="3.0.0"><shape type="sphere"/><sensor type="distant">{inner}</sensor></scene>"#
        ))
    };
    let s = sensor(&format!(
        r#"<vector name="direction" value="0, -2, 0"/>{film}"#
    ))
    .unwrap();
    assert_eq!(
        s.camera.projection,
        Projection::Distant {
            target: DistantTarget::BoundingDisk
        }
    );
    let z = s.camera.to_world.transform_vector3(Vec3::Z);
    assert!((z - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-6);
    let s = sensor(&format!(r#"<point name="target" value="1, 2, 3"/>{film}"#)).unwrap();
    assert_eq!(
        s.camera.projection,
        Projection::Distant {
            target: DistantTarget::Point(Vec3::new(1.0, 2.0, 3.0))
        }
    );
    let s = sensor(&format!(r#"<shape type="rectangle" name="target"/>{film}"#)).unwrap();
    assert_eq!(
        s.camera.projection,
        Projection::Distant {
            target: DistantTarget::Shape
        }
    );
    assert!(s.sensor_target.is_some() && s.shapes.len() == 1);
    for (inner, want) in [
        (String::new(), "needs a 1 x 1 film"),
        (
            format!(r#"<point name="target" value="0, 0, 0"/><shape type="disk"/>{film}"#),
            "not both",
        ),
        (
            format!(r#"<vector name="direction" value="0, 0, 0"/>{film}"#),
            "non-zero",
        ),
    ] {
        let e = sensor(&inner).unwrap_err();
        assert!(e.message.contains(want), "{inner}: {e}");
    }
}

/// `batch`: its nested sensors in order, the film's width divisible by their number; sensors
/// it cannot hold are located errors.
#[test]
fn batch_holds_its_sensors_in_order() {
    let batch = |inner: &str, width: u32| {
        load(&format!(
            r#"<scene version="3.0.0"><sensor type="batch">{inner}<film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="8"/></film></sensor></scene>"#
        ))
    };
    let two = r#"<sensor type="perspective"><float name="fov" value="30"/></sensor><sensor type="orthographic"/>"#;
    let s = batch(two, 16).unwrap();
    assert_eq!(s.camera.projection, Projection::Batch);
    assert_eq!(s.batch.len(), 2);
    assert!(matches!(
        s.batch[0].projection,
        Projection::Perspective { .. }
    ));
    assert_eq!(s.batch[1].projection, Projection::Orthographic);
    for (inner, width, want) in [
        (two, 15, "must be divisible"),
        ("", 16, "needs nested sensors"),
        (
            r#"<sensor type="batch"><sensor type="perspective"/></sensor>"#,
            16,
            "a batch holds perspective",
        ),
    ] {
        let e = batch(inner, width).unwrap_err();
        assert!(e.message.contains(want), "{inner}: {e}");
    }
}

#[test]
fn samplers_and_their_rounded_counts() {
    for (plugin, extra, asked, count, kind) in [
        ("independent", "", 10, 10, SamplerKind::Independent),
        (
            "stratified",
            "",
            10,
            16,
            SamplerKind::Stratified { jitter: true },
        ),
        (
            "multijitter",
            r#"<boolean name="jitter" value="false"/>"#,
            10,
            12,
            SamplerKind::MultiJitter { jitter: false },
        ),
        (
            "orthogonal",
            r#"<integer name="strength" value="2"/>"#,
            10,
            25,
            SamplerKind::Orthogonal { jitter: true },
        ),
        ("ldsampler", "", 5, 16, SamplerKind::LowDiscrepancy),
    ] {
        let s = load(&scene(&format!(
            r#"<sensor type="perspective"><sampler type="{plugin}"><integer name="sample_count" value="{asked}"/>{extra}</sampler></sensor>"#
        )))
        .unwrap();
        assert_eq!(
            (s.sampler.sample_count, s.sampler.kind),
            (count, kind),
            "{plugin}"
        );
    }
    // ldsampler has no jitter (Mitsuba's neither): an unused property.
    let e = fail(&scene(
        r#"<sensor type="perspective"><sampler type="ldsampler"><boolean name="jitter" value="true"/></sampler></sensor>"#,
    ));
    assert!(e.to_string().contains("jitter"), "{e}");
}

#[test]
fn direct_sample_counts_follow_mitsuba() {
    let direct = |body: &str| format!(r#"<integrator type="direct">{body}</integrator>"#);
    for (body, e, b) in [
        ("", 1, 1),
        (r#"<integer name="shading_samples" value="4"/>"#, 4, 4),
        (r#"<integer name="emitter_samples" value="0"/>"#, 0, 1),
        (
            r#"<integer name="bsdf_samples" value="0"/><integer name="emitter_samples" value="3"/>"#,
            3,
            0,
        ),
        (
            r#"<integer name="emitter_samples" value="2"/><integer name="bsdf_samples" value="3"/>"#,
            2,
            3,
        ),
    ] {
        let s = load(&scene(&direct(body))).unwrap();
        assert_eq!(
            s.integrator.kind,
            IntegratorKind::Direct {
                emitter_samples: e,
                bsdf_samples: b
            },
            "{body}"
        );
    }
    for (body, what) in [
        (
            r#"<integer name="shading_samples" value="2"/><integer name="bsdf_samples" value="2"/>"#,
            "either shading_samples",
        ),
        (
            r#"<integer name="emitter_samples" value="0"/><integer name="bsdf_samples" value="0"/>"#,
            "at least one",
        ),
    ] {
        let e = fail(&scene(&direct(body)));
        assert!(e.to_string().contains(what), "{body}: {e}");
    }
}
