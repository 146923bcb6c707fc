#!/usr/bin/env bash
# Sets up (installs missing Debian packages), builds and runs the whole test suite.
#   scripts/test.sh               Release build in build/
#   scripts/test.sh --sanitize    AddressSanitizer + UndefinedBehaviorSanitizer build in build-sanitize/
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh --tests

build_dir=build
source scripts/release_build.sh
configure() { configure_release_build; }
exclude=()
if [ "${1:-}" = "--sanitize" ]; then
  ./scripts/setup.sh --fuzz
  source scripts/sanitize_build.sh
  build_dir=$sanitize_build_dir
  configure() { configure_sanitize_build; }
  # Accuracy studies that run, on a larger case, the code a lighter test named beside each runs here too (the dent
  # refined: that test's fit refines too; several k-d blocks: two are), and the package's consumer build: the
  # sanitizers would see nothing new in them, and CI must stay within 30 minutes. The Release build runs them all.
  release_only=(
    ShapeSuite.ScanLinesAtThreeMicrometresAreFollowed                   # ShapeSuite.ScanLinesWithoutNoise...
    ShapeSuite.ScanLinesOnACylinderAreNotSplitBetweenTheLines           # ShapeSuite.ScanLinesAreFollowedOnEveryDraw...
                                                                        #   (noisy scan lines: the same split rule)
    Pipeline.TwoStyliWithoutNoiseAreExactOnASteepDent                   # Pipeline.TwoStyliOnOneFaceMeetTheBars
    Pipeline.GrossOutliersAtLowAndHighNoise                             # Pipeline.GrossOutliersMoveNoOtherPoint
    Pipeline.GrossOutliersAtLowAndHighNoiseWithTheBalancedPenalty       #   (its first case: the balance, 1 % moved,
    Pipeline.TheBalancedFitIsMadeAloneWhereNoGrossErrorCanBe            #   a rough first fit and balanced refits)
    Pipeline.GrossOutliersAreFlaggedAndDoNotSpoilTheirNeighbours        #   (the same)
    Pipeline.NoiseFreeDataWithGrossOutliersStateEveryErrorWithinItsU    #   (the same)
    Pipeline.AFewGrossOutliersAreLeftOutWithoutRegisteringAgain         #   (the same code, and the registration made again)
    Pipeline.UnfollowedShapeAtLowNoiseIsNotPeeledOff                    # Pipeline.NoiseFreeDataAreCompensated...
    ShapeSuite.OutliersSideBySideAreToldAsPossiblyShape                 # Pipeline.GrossOutliersMoveNoOtherPoint (the
                                                                        #   warning's code, on outliers apart)
    FitSurface.DataOnHalfThePatchWithTheDentFitThatHalf                 # FitSurface.ADentTheNominalKnotsCannotFollow...
    FitSurface.TheBalancedPenaltyFollowsANarrowDentWithoutRoughnessElsewhere  # FitSurface.ABroadMisfitTheSpan... (the
                                                                        #   balanced penalty), and every Pipeline test
                                                                        #   (it is the compensation's default)
    CrossValidation.OnScanLinesLeavingSpansOutKeepsTheNormalsBetweenTheLines  # the other CrossValidation tests
    Pipeline.FreeformCaseWithAnotherNoiseDrawMeetsTheBars               # Pipeline.FreeformCaseOnTheGridMeetsTheBars
    FreeformStudy.UncertaintyCoversTheTrueErrorOnThePanelAndInEachRegion_SteepDentLowNoise  # ..._RandomPointsLowNoise
    FitSurface.ADentTheNominalKnotsCannotFollowIsRefinedUntilTheResidualsAreNoise  # Pipeline.TheStepsComposeToCompensate
    NearestOthers.ACloudOfSeveralBlocksFindsWhatBruteForceFinds         # NearestOthers.TenThousandPointsInTwoBlocks...
    Pipeline.SameResultWithOneAndTwoThreads                             # the same code in every Pipeline test; what
                                                                        #   it checks (the same bits) is the numbers'
    CylinderStudies.DeformationCadBeatsConventionalAndSmoothsNoise      # CylinderStudies.MisalignmentCadBeats...
    Pipeline.ThreeThousandRandomPointsAtLowNoiseKeepEveryRow            # Pipeline.RandomShuffledPointsWithout...
    FreeformStudy.UncertaintyCoversTheTrueErrorOnThePanelAndInEachRegion_RandomPointsLowNoise  # FreeformStudy.APoint...
    package.consumer    # an outside project built against the installed package: its code is the library's, run here
    NistCharacteristics.CtcTwosProfilesAreJudgedInTheirDatumFramesAsTheirMovesSay  # NistCharacteristics.Stc*, Ftc*
                                                                        #   (the frames and characteristics; point
                                                                        #   targets in DatumFrame.PointTargets...)
    Pmi.MagnitudesAreReadInTheirUnitsOrNamedNotZero                     # fuzz_cad_step (the same reader, seeded with
    Pmi.MagnitudesInComplexEntitiesAreReadFromTheFilesOwnText           #   CTC-02's forms), Pmi.FtcSix... (read_pmi)
    Trim.DomainEdgeLinesOfTheDieCastSampleAgreeWithOpenCascade          # Trim.ALoopThatMeets... (the trim), and
                                                                        #   cli.shop_floor (the die-cast part read)
    NistCharacteristics.StcEightsProfilesAreJudgedInTheirDatumFramesAsTheirMovesSay  # DatumLocation.* (a part
                                                                        #   located by its datum features); StcSixs...
                                                                        #   and FtcSixs... (the NIST path)
  )
  exclude=(-E "^($(IFS='|'; echo "${release_only[*]}"))\$")
fi

configure
cmake --build "$build_dir" -j"$(nproc)"
ctest --test-dir "$build_dir" -j"$(nproc)" --output-on-failure "${exclude[@]}"
