"""The thesis's words behind each finding, quoted exactly (elisions marked " ... "; the thesis's own
typos kept), by finding key; the section each comes from is the finding's `section` (appendix A's
identity as section 4.2 restates it). Findings that read one statement two ways share its quote.
"""

QUOTES = {
    'appA_sed': (
        'for the plane strain models composed of an incompressible material, it can be shown that '
        'the strain energy density is proportional to the square of the magnitude of maximum '
        'compressive strain (See appendix A).'
    ),
    'appB_modulus': (
        'Hence, displacements and strains in a uniform plane strain finite element model with '
        "prescribed displacements and no prescribed forces are independent of the Young's modulus."
    ),
    'fig4-7_edge_pressure': (
        'The results for the four models indented to a depth of 1 mm by a 1.5 mm wide rectangular bar '
        'are shown in Figure 4-7. The surface loads imposed by the bars are shown along with the '
        'three strain measures at 0.75 mm depth. For each model, the intensity of the surface '
        'pressure is very high under the edge of the bar relative to the pressure at the center of '
        'the bar.'
    ),
    'fig4-7_model_contrast': (
        'The spatial distribution of the three strain measures shown are essentially low-pass '
        'filtered versions of the surface pressure distribution. The extent of the filtering depends '
        'on the model as well as the particular strain measure. For example, among the models, all '
        'the strain measures for the finite square case have superior contrast between the edges and '
        'the center of the bar, and the absolute shear strain has the best contrast among the strain '
        'measures for each model.'
    ),
    'fig4-7_shear_edges': (
        'For example, among the models, all the strain measures for the finite square case have '
        'superior contrast between the edges and the center of the bar, and the absolute shear strain '
        'has the best contrast among the strain measures for each model. Therefore, if a robot '
        'tactile sensing system needs to be designed to detect edges, the models predict that the '
        'best performance would be achieved by shear strain sensors.'
    ),
    'fig4-7_bone': (
        'A comparison of the strain energy profiles of the three models show that for the same '
        'stimulus, the distortion at the receptor location as measured by the strain energy density '
        'is the highest in the cylindrical model with bone. The effect of adding a stiff bone to the '
        'homogeneous cylindrical model can be seen in the increase in the maximum loads imposed and '
        'the accentuation of the strain energy density profile between the cylindrical model and the '
        'cylindrical model with bone.'
    ),
    'fig6-25_bar_depth': (
        'What is seen in Figure 6-25 is the ... "beam-like" effect in the variation of strains with '
        'depth. It can be recalled that strains in the classical beam solution are proportional to '
        'the distance of the point from the neutral axis. In this case, as the depth increases from '
        '0.75 to 1.0 mm the distance from the neutral axis increases, resulting in higher magnitudes '
        'of strains at a depth of 1.0 mm.'
    ),
    'fig7-4_local': (
        'In both the sections, the localized nature of the deformations is clearly seen from the '
        'contour plots. The deformation has a negligible effect on the magnitude of strain energy '
        'density about 3 mm from the edges of the bar. A large portion (85%) of the cross-section has '
        'less than 10 % of the maximum strain energy density indicating the local nature of spatial '
        'variation of strain energy density.'
    ),
    'sec7-1-2_gradual': (
        'Model m33338 shows an "elastic" deformation characterized by sharp changes in the magnitude '
        'of vertical displacements similar to the localized deformation observed in the 2D models '
        '(See Figure 4-27). The surface deformation of the m43338 model is more gradual as discussed '
        'in section 6.2.1 and can be seen in the right panel of Figure 7-4. ... Increase in the '
        'stiffness of the outer layer of the fingertip results in a wider area of contact and this '
        'counterintuitive phenomenon is discussed in detail in section 6.2.1.'
    ),
    'fig5-14_area': (
        'The bottom panel shows the variation with respect to the diameter of the indentor. It should '
        'be noted that the indentors were indented into the fingerpad to a fixed depth of indentation '
        'as shown in the legend. For smaller depths the area of contact varies linearly with the '
        'diameter of the indent ion.'
    ),
    'fig6-30_contact': (
        'The total area of contact is calculated and the radius of the circle with the same area is '
        'plotted for each indentor. The indentors are indented into the fingertip till a prescribed '
        'force is achieved and, hence, if the contact area increases with increase in indentor '
        'radius, the mean pressure would be expected to decrease. It can be observed that the maximum '
        'pressure also reduces with increase in radius of the indentor.'
    ),
    'fig4-24_depth': (
        'It can be seen that, the depth of indentation to achieve the prescribed force increased in '
        'proportion to the square root of the cylinder curvature for the solid model'
    ),
    'fig4-24_solid_fluid': (
        'To attain the same prescribed force, each cylinder had to be indented to a higher depth in '
        'the solid-fluid model than in the solid model. ... It can be seen that, the depth of '
        'indentation to achieve the prescribed force increased in proportion to the square root of '
        'the cylinder curvature for the solid model whereas there was no appreciable change for the '
        'solid-fluid model.'
    ),
    'fig4-25_contact': (
        'For each cylinder, the solid model had higher maximum pressure than the solid-fluid model '
        'and consequently had smaller contact widths. The contact width decreased with increase in '
        'curvature, and the reduction was more rapid for the solid-fluid model.'
    ),
    'sec6-2-1_dorsal': (
        'The local nature of the deformations can be understood from the contours shown in Figure '
        '6-5. The entire dorsal half and the proximal end of the fingertip have less than 10% of the '
        'maximum deformations.'
    ),
    'sec4-1_flamant': (
        'The availability of analytical solutions to a line load acting upon a semi-infinite linear '
        'elastic medium (Timoshenko and Goodier, 1982) provides a means of verifying the finite '
        'element calculations. ... Model dimensions of 40mm x 18mm containing 8-noded plane strain '
        'isoparametric elements were sufficient to match the analytical results in the region of '
        'interest.'
    ),
    'fig4-19_gaps': (
        'If it is assumed that the spatial variation in the shear strain at the receptor location is '
        'used in determining the location of the edges of the stimulus and, hence, the width of a gap '
        'indented into the fingerpad, then, variation in the slope and the distance between the two '
        'peaks of the shear strain will be the cues used by subjects in detection and discrimination. '
        "... The knee in the variation of d' in the experimental and finite element data agree "
        'closely. The experimental data is available till 1.0 mm width and the simulation data '
        "predicts a settling trend in the variation of d' as against the linear extrapolation in the "
        'experimental data.'
    ),
    'fig4-10_bars_in_contact': (
        'Only a few bars are in contact with the cylindrical finger during any one indentation, as '
        'contrasted with contact with all the bars in the case of the semiinfinite model. ... As the '
        'gratings are indented with a prescribed displacement, the total force imposed on the models '
        'is not the same. As only a few bars come in contact with the cylindrical model, the area '
        'over which the force acts is also different in the two models.'
    ),
    'fig4-11_neighbours': (
        'It can be observed from Figure 4-11 that the calculated strains at a fixed location under an '
        'individual bar of the grating depend on the spacing of the neighboring bars when two or more '
        'bars are in contact with the fingerpad. ... the finite element calculations predict almost '
        'identical strain states under each of the three rightmost bars which have the largest gaps '
        'between them. When the gaps are less than 1.5 mm, the strain state of the receptor is '
        'influenced ... by the contacting bars neighboring the one directly above the receptor.'
    ),
    'fig4-12_diameter': (
        'In the left panels the rightmost bar (#1) is above the center of the fingertip and there is '
        'no significant difference in loading between 8 mm and 16 mm models as bar #2 barely touches '
        'the 16 mm model. ... Due to the higher curvature of the 8 mm model, the neighboring bars 1 '
        'and 3 barely touch the model, whereas in the 16 mm model both bars 1 and 3 indent the '
        'fingertip.'
    ),
    'sec4-5-3_rightmost_bars': (
        'The same experiment was simulated using the 16 mm diameter model and the the predicted and '
        'experimentally observed spatial response profiles for gratings with 0.5 mm and 1.5 mm bars '
        'are shown in Figures 4-13 and 4-14 respectively. It can be observed that the response for '
        'the two rightmost bars is not identical as was the case for 8 mm diameter model. '
        'Consequently, the goodness of fit is better than the 8 mm model.'
    ),
    'fig4-18_off_centre': (
        'For a semi-infinite model, this would be identical to the population response and the '
        'response of any other receptor at the same depth irrespective of its lateral location. The '
        'middle and bottom traces in Figure 4-18 show the difference between the *spatial response '
        'profile* predicted by receptors which are off-center by 1 and 2 mm respectively. ... These '
        'profiles are different even when sensitivity and threshold are the same for all three units.'
    ),
    'sec4-5-4_central_profiles': (
        'In spite of drastic differences in the geometry and resulting strain distributions under a '
        'single indentation by a grating (Figure 4-10) among the cylindrical and semi-infinite '
        'models, the calculated spatial profiles shown in Figure 4-11 are surprisingly similar to '
        'those obtained by Phillips and Johnson (1981b). ... Therefore, although the calculated '
        'strain fields and, hence, the predicted population responses are very different for '
        'cylindrical and semi-infinite models, the spatial profiles of a strain measure for the two '
        'models are similar at a central receptor location.'
    ),
    'fig6-10_layers': (
        'This location can be graphically determined by locating the point where the vertical '
        'distance between the two extreme traces is the maximum and is approximately around 2.0 mm '
        'away from the line load. ... The horizontal location most affected by the changes is now '
        'around 1.3 mm from the line load ... For all the points less than about 1.25 mm from the '
        "location of the line load, increasing the Young's modulus of layer #2 causes a decrease in "
        'stiffness of the model, similar to the behavior of the outermost layer. At all horizontal '
        "locations more than 1.25 mm away from the line load, increasing the Young's modulus of layer "
        '#2 causes an increase in the stiffness of the model, which is similar to the effect observed '
        'in case of layer #3 and #4.'
    ),
    'fig4-27_line_load': (
        'It can be seen that the profiles for the semi-infinite and finite square models are close '
        'together, as are those for the ... cylinder with and without the bone. If the vertical '
        'deflection, say at 2 mm from the load, is taken as a measure of the overall stiffness of the '
        'models, then the four finite element models in increasing order of stiffness are the finite '
        'square, semi-infinite, cylinder and cylinder with bone.'
    ),
    'fig4-3_depth': (
        'For each of the components, the deeper the location, the more blurred is the spatial '
        'distribution. This illustrates the spatial low-pass filtering of the mechanical signals by '
        'the elastic medium and shows that the quality of information about the spatial variation of '
        'the surface stimulus decreases with increases in the depth of receptor locations. ... For a '
        'given receptor depth, the degree of blurring of the strain energy density distribution is '
        'less than that of the maximum compressive strain (Srinivasan and Dandekar, 1991).'
    ),
    'fig4-3_models': (
        'For the three other models described above, although the magnitudes of the stresses and '
        'strains at a given location are different for a given line load, the general spatial profile '
        'of each component is approximately the same as the corresponding one for the cylindrical '
        'model.'
    ),
    'fig4-4_receptive_fields': (
        'It can be seen that maximum compressive strain predicts a circular receptive field, with the '
        'center of the circle being the most sensitive spot. Strain energy density predicts a similar '
        'receptive field with a circular region centered directly above the receptor as the region in '
        'which the receptor would respond. ... The diameter of the OFF circle in the receptive field '
        'for absolute shear strain is about 0.3 mm.'
    ),
    'sec4-2_reciprocity': (
        'We will assume that the state of stress at the receptor below B, when the fingertip is '
        'indented by a point load on the skin at A is the same at the state of stress at the receptor '
        'below the point A when the fingertip is indented by a point load on the skin at point B. '
        'This would be the case for a semi-infinite model, but this is a reasonable approximation for '
        'the case of 2D cylindrical model, since we are restricting the discussion to a centrally '
        'located single point load and two points A and B are a short distance apart compared to the '
        'fingertip diameter.'
    ),
    'fig7-2_eps1': (
        'The maximum compressive strain shown in the bottom panel is approximately equal in magnitude '
        'and form in the two models. ... The maximum compressive strain in the 3D model is slightly '
        'higher than the 2D model, indicating that the 2D model is stiffer than the 3D model, which '
        'is to be expected since the plane strain assumption is used in the analysis of the 2D model.'
    ),
    'fig7-2_sed': (
        'There is a difference in the magnitude of maximum strain energy density predicted by the 2D '
        'and the 3D models. In the 2D models, constraining of the deformations to the plane is '
        'equivalent to assuming the stiffness in the axial direction to be infinite. Consequently, '
        'when the bar is indented to a depth of 1.0 mm into the fingertip regardless of the force '
        'required for the indentation, the 2D model being stiffer predicts a higher strain energy '
        'density.'
    ),
    'fig7-3_off_centre': (
        'Figure 7-3 shows a comparison of the strain measures from the 2D model and an axial section '
        'of the 3D model at z = 9.17, which is about 2 mm away from the node with the maximum '
        'prescribed displacement. ... The magnitudes of the maximum compressive strain in the 2D and '
        '3D models are not equal at z = 9.17, and, all the strain measures in this cross-section are '
        'lower than the section at z = 7.495. This is to be expected because the curvature of the '
        'finger in the YZ plane causes the maximum depth of indentation for the nodes in this '
        'cross-section to be less than 1.0 mm, which was the corresponding maximum in the section at '
        'z = 7.495.'
    ),
    'fig6-39_step_extremes': (
        'The contact area is minimum under the regions of the step that have high convex curvature. '
        'When the concave part of the step is over the fingertip model, the contact area is the '
        'highest and is accompanied by the lowest magnitude of the maximum pressure in the contact '
        'region.'
    ),
    'fig6-39_step_inverse': (
        'As in the case of cylindrical indentors indented with constant force, it can be seen that an '
        'increase in the contact area is always accompanied by a decrease in the maximum contact '
        'pressure and vice-versa.'
    ),
    'fig6-38_spatial_response': (
        'For an identical stimulus, the spatial location of the mechanoreceptor can influence the '
        'form of the spatial response profile. ... The curvature of the fingertip and other factors '
        'discussed earlier, affect the stress- ... state in the vicinity of the receptors resulting '
        'in different spatial response profiles as shown in Figure 6-38.'
    ),
    'fig4-5_two_point': (
        'In the prescribed displacement case, as the load spacing increases from zero, the peak value '
        'of strain energy density increases at first, then decreases sharply, followed by a gradual '
        'increase till it attains a steady value. On the other hand, in the prescribed force case, '
        'the peak value monotonically decreases and settles down to a steady value at a load spacing '
        'much smaller than the corresponding one in the prescribed displacement case.'
    ),
    'fig4-6_intensive_cue': (
        'The explanation for the difference stems from the fact that surface displacement due to each '
        'load spreads (semi-width of about 2 mm) much wider than the corresponding sub-surface strain '
        'energy distribution at the depth of interest (semi-width of about 1 mm for depths 0.5 to 1.0 '
        'mm) (Srinivasan and Dandekar, 1994a). ... It can be seen from Figure 4-6 that, in the '
        'prescribed displacement case the intensive cues continue to vary with the load separation, '
        'whereas, the intensive cues settle down to a constant value at a separation of 1.6 mm for '
        'the prescribed force case.'
    ),
}
