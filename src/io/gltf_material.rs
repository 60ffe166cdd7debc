//! glTF 2.0 materials (glTF 2.0 specification, sec. 3.9 "Materials"): a primitive's
//! `baseColorFactor` (linear) and `baseColorTexture` (PNG or JPEG, sRGB; file, `data:` URI or
//! buffer view) with its sampler's filter and `wrapS`, as the mesh layer's [`FileMaterial`].

use std::path::Path;

use glam::DVec3;

use super::gltf::{resolve_uri, UriTarget};
use super::gltf_accessor::Reader;
use super::mesh::{FileMaterial, FileTexture, TextureSource};
use crate::error::{Error, Result};
use crate::scene::image_texture::{Filter, Wrap};

/// A primitive's material as the mesh layer describes it.
pub(super) fn file_material(
    r: &Reader,
    at: &str,
    material: &gltf::Material,
    vertex_colors: bool,
    has_uvs: bool,
    warnings: &mut Vec<String>,
) -> Result<FileMaterial> {
    let path = r.path;
    let Some(index) = material.index() else {
        return Ok(FileMaterial { vertex_colors, ..Default::default() });
    };
    let pbr = material.pbr_metallic_roughness();
    let [cr, cg, cb, _] = pbr.base_color_factor().map(f64::from);
    let base_color = DVec3::new(cr, cg, cb);
    let at_m = format!("materials[{index}]");
    if !base_color.is_finite() || base_color.min_element() < 0.0 {
        return Err(Error::parse(path, format!("{at_m}.baseColorFactor: must be finite and >= 0, got {base_color}")));
    }
    let texture = match pbr.base_color_texture() {
        None => None,
        Some(_) if !has_uvs => {
            warnings.push(format!(
                "{}: {at}: {at_m} has a base colour texture but the primitive has no texture coordinates; texture ignored",
                path.display()
            ));
            None
        }
        Some(info) => {
            let tex = info.texture();
            let image = tex.source();
            let at_img = format!("images[{}]", image.index());
            // The image's bytes or file; an image that cannot be had loses the texture, with a
            // warning (the base colour is used), as a missing image file does later.
            let source = match image.source() {
                gltf::image::Source::View { view, .. } => {
                    let buffer = &r.buffers[view.buffer().index()];
                    match buffer.get(view.offset()..view.offset() + view.length()) {
                        Some(bytes) => Ok(TextureSource::Embedded { name: at_img.clone(), bytes: bytes.to_vec() }),
                        None => Err(format!("bufferViews[{}] runs past the end of its buffer", view.index())),
                    }
                }
                gltf::image::Source::Uri { uri, .. } => {
                    match resolve_uri(path, path.parent().unwrap_or(Path::new("")), r.reach, &at_img, uri) {
                        Ok(UriTarget::Data(bytes)) => Ok(TextureSource::Embedded { name: at_img.clone(), bytes }),
                        Ok(UriTarget::File(file)) => Ok(TextureSource::File(file)),
                        // A file outside the scene's folder is refused, not lost with a warning.
                        Err(e @ Error::Parse { .. }) if !uri.starts_with("data:") && !uri.contains("://") => {
                            return Err(e)
                        }
                        Err(Error::Parse { message, .. }) => Err(message),
                        Err(e) => Err(e.to_string()),
                    }
                }
            };
            match source {
                Err(why) => {
                    warnings.push(format!(
                        "{}: {at_m}{}: the base colour texture cannot be read ({why}); the base colour is used",
                        path.display(),
                        material.name().map(|n| format!(" ('{n}')")).unwrap_or_default()
                    ));
                    None
                }
                Ok(source) => {
                    let sampler = tex.sampler();
                    let filter = match sampler.mag_filter() {
                        Some(gltf::texture::MagFilter::Nearest) => Filter::Nearest,
                        _ => Filter::Bilinear,
                    };
                    let wrap = match sampler.wrap_s() {
                        gltf::texture::WrappingMode::ClampToEdge => Wrap::Clamp,
                        gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
                        gltf::texture::WrappingMode::MirroredRepeat => {
                            warnings.push(format!(
                                "{}: {at_m}: mirrored-repeat texture wrapping is read as repeat",
                                path.display()
                            ));
                            Wrap::Repeat
                        }
                    };
                    Some(FileTexture { source, filter: Some(filter), wrap: Some(wrap) })
                }
            }
        }
    };
    Ok(FileMaterial {
        name: material.name().map(String::from),
        base_color: Some(base_color),
        texture,
        untextured_color: None,
        vertex_colors,
    })
}
